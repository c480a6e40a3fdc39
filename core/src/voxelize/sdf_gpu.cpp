// The signed distance field's band slab by slab on a device: the CUDA GPU,
// or the host emulation of its kernel. See voxd/detail/sdf_gpu.h.
#include "voxd/detail/sdf_gpu.h"

#include <algorithm>
#include <array>
#include <mutex>
#include <string>
#include <vector>

#include <glm/common.hpp>

#include "voxd/error.h"
#include "voxd/parallel.h"
#include "voxelize/gpu_gate.h"
#include "voxelize/sdf_band.h"
#include "voxelize/sdf_device.h"

namespace voxd::sdf {
namespace {

// The kernel's work on the CPU: each brick's triangles gathered (as the GPU
// stages them in shared memory), then each of its voxels through the same
// per-voxel functions. Parallel over bricks.
class HostBandDevice final : public SdfBandDevice {
 public:
  explicit HostBandDevice(int threads) : threads_(threads) {}

  void begin(const SdfBandScene& scene, std::int64_t) override {
    scene_ = &scene;
    const std::size_t n = scene.triangles.size() / 3;
    triangles_.resize(n);
    parallel_for(0, static_cast<std::int64_t>(n), 4096, threads_, [&](std::int64_t a, std::int64_t b) {
      for (auto t = static_cast<std::size_t>(a); t < static_cast<std::size_t>(b); ++t) {
        const std::uint32_t* v = &scene.triangles[3 * t];
        triangles_[t] = device_triangle(&scene.vertices[3 * std::size_t{v[0]}], &scene.vertices[3 * std::size_t{v[1]}],
                                        &scene.vertices[3 * std::size_t{v[2]}]);
      }
    });
  }

  void band(std::int64_t k0, std::int64_t layers, float* out) override {
    const SdfBandParams& p = scene_->params;
    const std::int64_t nx = p.dims[0], ny = p.dims[1];
    const std::int64_t bz0 = k0 / kBrick, bz1 = (k0 + layers + kBrick - 1) / kBrick;
    const std::int64_t per_layer = p.bricks[0] * p.bricks[1];
    parallel_for(0, (bz1 - bz0) * per_layer, 16, threads_, [&](std::int64_t a, std::int64_t b) {
      std::vector<DeviceTriangle> staged;
      for (std::int64_t item = a; item < b; ++item) {
        const std::int64_t bx = item % p.bricks[0], by = item / p.bricks[0] % p.bricks[1], bz = bz0 + item / per_layer;
        const auto brick = static_cast<std::size_t>(bx + p.bricks[0] * (by + p.bricks[1] * bz));
        staged.clear();
        for (std::uint64_t x = scene_->brick_offsets[brick]; x < scene_->brick_offsets[brick + 1]; ++x)
          staged.push_back(triangles_[scene_->brick_triangles[x]]);
        for (std::int64_t k = bz * kBrick; k < std::min((bz + 1) * kBrick, k0 + layers); ++k)
          for (std::int64_t j = by * kBrick; j < std::min((by + 1) * kBrick, ny); ++j)
            for (std::int64_t i = bx * kBrick; i < std::min((bx + 1) * kBrick, nx); ++i) {
              const double best = nearest2(staged.data(), static_cast<int>(staged.size()), voxel_centre(p, i, j, k),
                                           HUGE_VAL);
              out[((k - k0) * ny + j) * nx + i] = band_value(p, best);
            }
      }
    });
  }

 private:
  int threads_;
  const SdfBandScene* scene_ = nullptr;
  std::vector<DeviceTriangle> triangles_;
};

// The mesh and its triangles listed by the bricks their band can reach: a
// triangle's box in index space, widened by the band and a voxel more
// (rounding here is far below that), clamped to the grid.
std::unique_ptr<const SdfBandScene> make_scene(const Mesh& mesh, const Grid& grid, const BandSetup& s, float clamped,
                                               int threads) {
  auto scene = std::make_unique<SdfBandScene>();
  SdfBandParams& p = scene->params;
  for (int a = 0; a < 3; ++a) {
    p.origin[a] = grid.origin[a];
    p.dims[a] = grid.dims[a];
    p.bricks[a] = (grid.dims[a] + kBrick - 1) / kBrick;
  }
  p.voxel_size = grid.voxel_size;
  p.to_output = s.to_output;
  p.clamped = clamped;
  scene->vertices.reserve(3 * mesh.vertices.size());
  for (const glm::vec3& v : mesh.vertices) scene->vertices.insert(scene->vertices.end(), {v.x, v.y, v.z});
  scene->triangles.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles) scene->triangles.insert(scene->triangles.end(), t.begin(), t.end());

  const IndexSpace index_of(grid);
  const double reach = s.band * index_of.inv_voxel + 1.0;  // voxels
  const std::size_t n = mesh.triangles.size();
  // Each triangle's bricks, [lo, hi] per axis (lo > hi: none).
  std::vector<std::array<std::int32_t, 6>> boxes(n);
  parallel_for(0, static_cast<std::int64_t>(n), 4096, threads, [&](std::int64_t a, std::int64_t b) {
    for (auto t = static_cast<std::size_t>(a); t < static_cast<std::size_t>(b); ++t) {
      const dvec3 c0 = index_of(dvec3(mesh.corner(t, 0))), c1 = index_of(dvec3(mesh.corner(t, 1))),
                  c2 = index_of(dvec3(mesh.corner(t, 2)));
      const dvec3 lo = glm::min(glm::min(c0, c1), c2), hi = glm::max(glm::max(c0, c1), c2);
      auto& box = boxes[t];
      for (int axis = 0; axis < 3; ++axis) {
        const std::int64_t first = IndexSpace::first(lo[axis] - reach, grid.dims[axis]);
        const std::int64_t last = IndexSpace::last(hi[axis] + reach, grid.dims[axis]);
        box[axis] = static_cast<std::int32_t>(first / kBrick);
        box[axis + 3] = first <= last ? static_cast<std::int32_t>(last / kBrick) : box[axis] - 1;
      }
    }
  });
  const auto brick_index = [&p](std::int64_t x, std::int64_t y, std::int64_t z) {
    return static_cast<std::size_t>(x + p.bricks[0] * (y + p.bricks[1] * z));
  };
  scene->brick_offsets.assign(static_cast<std::size_t>(p.bricks[0] * p.bricks[1] * p.bricks[2]) + 1, 0);
  const auto for_each_brick = [&](const std::array<std::int32_t, 6>& box, const auto& visit) {
    for (std::int64_t z = box[2]; z <= box[5]; ++z)
      for (std::int64_t y = box[1]; y <= box[4]; ++y)
        for (std::int64_t x = box[0]; x <= box[3]; ++x) visit(brick_index(x, y, z));
  };
  for (const auto& box : boxes) for_each_brick(box, [&](std::size_t b) { ++scene->brick_offsets[b + 1]; });
  for (std::size_t b = 1; b < scene->brick_offsets.size(); ++b) scene->brick_offsets[b] += scene->brick_offsets[b - 1];
  scene->brick_triangles.resize(scene->brick_offsets.back());
  std::vector<std::uint64_t> cursor(scene->brick_offsets.begin(), scene->brick_offsets.end() - 1);
  for (std::size_t t = 0; t < n; ++t)
    for_each_brick(boxes[t], [&](std::size_t b) { scene->brick_triangles[cursor[b]++] = static_cast<std::uint32_t>(t); });
  return scene;
}

}  // namespace

void band_on_device(detail::SdfBackend backend, const Mesh& mesh, const Grid& grid, const BandSetup& s, float clamped,
                    int threads, std::uint64_t gpu_memory, DenseVolume<float>& values,
                    const detail::ProgressSpan& progress, DeviceRunReport* report) {
  if (backend == detail::SdfBackend::cuda && !cuda_unavailable_reason().empty())
    throw Error(ErrorCode::invalid_argument, cuda_unavailable_reason());
  const auto scene = make_scene(mesh, grid, s, clamped, threads);
  std::unique_lock<std::mutex> gate;
  std::unique_ptr<SdfBandDevice> device;
  std::uint64_t budget = gpu_memory;
  if (backend == detail::SdfBackend::cuda) {
    gate = std::unique_lock<std::mutex>(detail::gpu_gate());
    device = make_cuda_sdf_device(budget);
  } else {
    device = std::make_unique<HostBandDevice>(threads);
    if (budget == 0)
      budget = scene->bytes() + detail::sdf_layer_bytes(grid) *
                                    static_cast<std::uint64_t>((grid.dims.z + kBrick - 1) / kBrick * kBrick);
  }
  const detail::SdfSlabPlan plan = detail::plan_sdf_slabs(grid, scene->bytes(), budget);
  device->begin(*scene, plan.layers_per_slab);
  for (std::int64_t k0 = 0; k0 < grid.dims.z; k0 += plan.layers_per_slab) {
    progress.check_cancelled();
    const std::int64_t n = std::min(plan.layers_per_slab, grid.dims.z - k0);
    device->band(k0, n, values.slab(k0));
    progress.report(static_cast<double>(k0 + n) / static_cast<double>(grid.dims.z));
  }
  if (report) {
    report->device = backend == detail::SdfBackend::cuda ? ComputeDevice::cuda : ComputeDevice::cpu;
    report->slabs = plan.slabs;
    report->passes = plan.slabs;
    report->gpu_bytes = plan.device_bytes;
    report->gpu_kernel_ms = device->kernel_ms();
    report->gpu_copy_ms = device->copy_ms();
    report->gpu_measured_bytes = device->measured_bytes();
  }
}

std::uint64_t scene_bytes(const Mesh& mesh, const Grid& grid, const BandSetup& s, float clamped) {
  return make_scene(mesh, grid, s, clamped, default_thread_count())->bytes();
}

}  // namespace voxd::sdf

namespace voxd::detail {

std::uint64_t sdf_layer_bytes(const Grid& grid) {
  return static_cast<std::uint64_t>(grid.dims.x) * static_cast<std::uint64_t>(grid.dims.y) * sizeof(float);
}

SdfSlabPlan plan_sdf_slabs(const Grid& grid, std::uint64_t scene_bytes, std::uint64_t budget) {
  SdfSlabPlan plan;
  if (grid.voxel_count() == 0) return plan;
  const std::uint64_t bricks = sdf_layer_bytes(grid) * sdf::kBrick;
  if (budget < scene_bytes || (budget - scene_bytes) / bricks < 1)
    throw Error(ErrorCode::limit_exceeded,
                "the GPU memory budget of " + std::to_string(budget) + " bytes cannot hold the mesh (" +
                    std::to_string(scene_bytes) + " bytes with its bricks) and " + std::to_string(sdf::kBrick) +
                    " z layers of the " + std::to_string(grid.dims.x) + " x " + std::to_string(grid.dims.y) +
                    " grid (" + std::to_string(bricks) + " bytes); raise the budget or use device cpu");
  const std::uint64_t fit = (budget - scene_bytes) / bricks * sdf::kBrick;
  plan.layers_per_slab = static_cast<std::int64_t>(std::min<std::uint64_t>(fit, static_cast<std::uint64_t>(grid.dims.z)));
  plan.slabs = (grid.dims.z + plan.layers_per_slab - 1) / plan.layers_per_slab;
  plan.device_bytes = scene_bytes + static_cast<std::uint64_t>(plan.layers_per_slab) * sdf_layer_bytes(grid);
  return plan;
}

}  // namespace voxd::detail
