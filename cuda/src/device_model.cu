// Uploading a GwnModel's arrays to the device (the owner DeviceModel, the views it hands out),
// and whether a device can be used at all.
#include "device_model.cuh"

namespace gwnrt::cuda {

bool device_available(std::string* why) {
  int count = 0;
  const cudaError_t err = cudaGetDeviceCount(&count);
  if (err != cudaSuccess || count == 0) {
    if (why)
      *why = err != cudaSuccess ? std::string("no usable CUDA device: ") + cudaGetErrorString(err)
                                : std::string("no CUDA device found");
    cudaGetLastError();  // clear the sticky error so later calls start clean
    return false;
  }
  return true;
}

uint64_t free_device_memory() {
  size_t free = 0, total = 0;
  if (cudaMemGetInfo(&free, &total) != cudaSuccess) {
    cudaGetLastError();
    return 0;
  }
  return free;
}

DeviceModel::DeviceModel() = default;
DeviceModel::~DeviceModel() = default;
DeviceModel::DeviceModel(DeviceModel&&) noexcept = default;
DeviceModel& DeviceModel::operator=(DeviceModel&&) noexcept = default;

ModelView DeviceModel::view() const { return buffers_ ? buffers_->view : ModelView{}; }

Status DeviceModel::upload(const GwnModel& model, DeviceModel& out) {
  return guard_status("DeviceModel::upload", [&]() -> Status {
    std::string why;
    if (!device_available(&why)) return {StatusCode::kUnavailable, why};
    // Every part the model may be asked: the device's copy is not built on first need.
    if (Status s = model.prepare(kPartBoundary | kPartSheets | kPartLevelFreeCells); !s.ok()) return s;
    auto b = std::make_unique<Buffers>();
    // Same views as on the host (counts, bounds), with device pointers in place of host ones.
    ModelView v = model.view();
    if (Status s = b->triangles.upload(model.triangle_tree(), v.triangles); !s.ok()) return s;
    if (Status s = b->cone.upload(model.cone_tree(), v.cone); !s.ok()) return s;
    if (Status s = b->sheets.upload(model.sheet_tree(), v.sheets); !s.ok()) return s;
    const SegmentTree& st = model.boundary_tree();
    const std::span<const WideNodeLength> lengths = model.cone_boundary_lengths();
    const std::span<const ConeSegment> segments = model.cone_segments();
    for (Status s : {b->cone_lengths.upload(lengths.data(), lengths.size()),
                     b->cone_segments.upload(segments.data(), segments.size()), b->segment_nodes.upload(st.bvh.nodes),
                     b->segment_lengths.upload(st.lengths), b->segment_net_lengths.upload(st.net_lengths),
                     b->endpoints.upload(st.endpoints), b->segment_ids.upload(st.segment_ids),
                     b->smooth_regions.upload(model.smooth_regions().data(), model.smooth_regions().size()),
                     b->level_free.upload(model.level_free_cells().free.data(), model.level_free_cells().free.size())})
      if (!s.ok()) return s;
    v.smooth_regions = b->smooth_regions.get();
    v.level_free.free = v.level_free.free ? b->level_free.get() : nullptr;
    v.cone_boundary_lengths = b->cone_lengths.get();
    v.cone_segments = b->cone_segments.get();
    v.boundary.bvh.nodes = b->segment_nodes.get();
    v.boundary.lengths = b->segment_lengths.get();
    v.boundary.net_lengths = b->segment_net_lengths.get();
    v.boundary.endpoints = b->endpoints.get();
    v.boundary.segment_ids = b->segment_ids.get();
    v.ribbons = RibbonTreeView{};  // host only (model_view.h)
    b->view = v;
    out.buffers_ = std::move(b);
    return Status::Ok();
  });
}

}  // namespace gwnrt::cuda
