// DeviceModel's buffers (the model's arrays in device memory, and the batches' scratch) and the
// batches' access to them: what cuda/src's .cu files share.
#pragma once

#include <mutex>

#include "device_buffer.h"
#include "gwnrt/cuda.h"

namespace gwnrt::cuda {

// One multipole triangle tree in device memory (M itself, the cone C over ∂M, the sheets).
struct DeviceTriangleTree {
  DeviceBuffer<WideNode> nodes;
  DeviceBuffer<WideNodeExpansion> expansion;
  DeviceBuffer<WideNodeOrder1> order1;
  DeviceBuffer<WideNodeOrder2> order2;
  DeviceBuffer<vec3> vertices;
  DeviceBuffer<uint32_t> triangle_ids;

  // Uploads `tree` and points `view` (the host view of it) at the device copies.
  Status upload(const TriangleTree& tree, TriangleTreeView& view) {
    for (Status s :
         {nodes.upload(tree.bvh.nodes), expansion.upload(tree.expansion), order1.upload(tree.order1),
          order2.upload(tree.order2), vertices.upload(tree.vertices), triangle_ids.upload(tree.triangle_ids)})
      if (!s.ok()) return s;
    view.bvh.nodes = nodes.get();
    view.expansion = expansion.get();
    view.order1 = order1.get();
    view.order2 = order2.get();
    view.vertices = vertices.get();
    view.triangle_ids = triangle_ids.get();
    view.corner_columns = nullptr;  // host only (bvh.h)
    view.column_stride = 0;
    return Status::Ok();
  }
};

// Device memory a batch copies its inputs and results through, kept from batch to batch and
// grown (by half again, at least to what is asked) when one needs more: a batch of queries
// pays no cudaMalloc or cudaFree.
class DeviceScratch {
 public:
  // At least `bytes` bytes (aligned for any element type). Fails naming the size.
  Status reserve(size_t bytes) {
    if (bytes <= buffer_.size()) return Status::Ok();
    const size_t grown = buffer_.size() + buffer_.size() / 2;
    return buffer_.allocate(grown > bytes ? grown : bytes);
  }
  void* get() const { return buffer_.get(); }

 private:
  DeviceBuffer<unsigned char> buffer_;
};

struct DeviceModel::Buffers {
  DeviceTriangleTree triangles;
  DeviceTriangleTree cone;
  DeviceTriangleTree sheets;
  DeviceBuffer<WideNodeLength> cone_lengths;
  DeviceBuffer<ConeSegment> cone_segments;
  DeviceBuffer<WideNode> segment_nodes;
  DeviceBuffer<WideNodeLength> segment_lengths;
  DeviceBuffer<WideNodeLength> segment_net_lengths;
  DeviceBuffer<vec3> endpoints;
  DeviceBuffer<uint32_t> segment_ids;
  DeviceBuffer<SmoothRegion> smooth_regions;
  DeviceBuffer<uint8_t> level_free;  // LevelFreeCells::free
  ModelView view;
  std::mutex scratch_mutex;  // one batch at a time uses the scratch
  DeviceScratch inputs, results;
};

struct DeviceAccess {
  using Buffers = DeviceModel::Buffers;
  static Buffers* buffers(const DeviceModel& model) { return model.buffers_.get(); }
};

}  // namespace gwnrt::cuda
