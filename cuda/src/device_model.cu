#include "device_buffer.h"
#include "gwnrt/cuda.h"

namespace gwnrt::cuda {

struct DeviceModel::Buffers {
  DeviceBuffer<WideNode> triangle_nodes;
  DeviceBuffer<WideNodeExpansion> expansion;
  DeviceBuffer<WideNodeOrder1> order1;
  DeviceBuffer<WideNodeOrder2> order2;
  DeviceBuffer<vec3> vertices;
  DeviceBuffer<uint32_t> triangle_ids;
  DeviceBuffer<WideNode> segment_nodes;
  DeviceBuffer<vec3> endpoints;
  DeviceBuffer<uint32_t> segment_ids;
  ModelView view;
};

bool device_available(std::string* why) {
  int count = 0;
  const cudaError_t err = cudaGetDeviceCount(&count);
  if (err != cudaSuccess || count == 0) {
    if (why) *why = err != cudaSuccess ? std::string("no usable CUDA device: ") + cudaGetErrorString(err)
                                       : std::string("no CUDA device found");
    cudaGetLastError();  // clear the sticky error so later calls start clean
    return false;
  }
  return true;
}

DeviceModel::DeviceModel() = default;
DeviceModel::~DeviceModel() = default;
DeviceModel::DeviceModel(DeviceModel&&) noexcept = default;
DeviceModel& DeviceModel::operator=(DeviceModel&&) noexcept = default;

ModelView DeviceModel::view() const { return buffers_ ? buffers_->view : ModelView{}; }

Status DeviceModel::upload(const GwnModel& model, DeviceModel& out) {
  std::string why;
  if (!device_available(&why)) return {StatusCode::kUnavailable, why};
  auto b = std::make_unique<Buffers>();
  const TriangleTree& tt = model.triangle_tree();
  const SegmentTree& st = model.boundary_tree();
  for (Status s : {b->triangle_nodes.upload(tt.bvh.nodes), b->expansion.upload(tt.expansion), b->order1.upload(tt.order1),
                   b->order2.upload(tt.order2), b->vertices.upload(tt.vertices), b->triangle_ids.upload(tt.triangle_ids),
                   b->segment_nodes.upload(st.bvh.nodes), b->endpoints.upload(st.endpoints),
                   b->segment_ids.upload(st.segment_ids)})
    if (!s.ok()) return s;
  // Same views as on the host, with device pointers in place of host ones.
  ModelView v = model_view(model);
  v.triangles.bvh.nodes = b->triangle_nodes.get();
  v.triangles.expansion = b->expansion.get();
  v.triangles.order1 = b->order1.get();
  v.triangles.order2 = b->order2.get();
  v.triangles.vertices = b->vertices.get();
  v.triangles.triangle_ids = b->triangle_ids.get();
  v.boundary.bvh.nodes = b->segment_nodes.get();
  v.boundary.endpoints = b->endpoints.get();
  v.boundary.segment_ids = b->segment_ids.get();
  b->view = v;
  out.buffers_ = std::move(b);
  return Status::Ok();
}

}  // namespace gwnrt::cuda
