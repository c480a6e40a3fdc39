#include "server/jobs/slab_tasks.h"

#include <algorithm>
#include <charconv>

#include "voxd/bit_volume.h"

namespace voxd::server {
namespace {

// A job id never holds '/': "ID/slab/I" is a task.
constexpr std::string_view kTaskMark = "/slab/";

}  // namespace

LayerRange SlabTaskPlan::range(std::int64_t index, std::int64_t nz) const {
  const std::int64_t begin = index * task_layers;
  return {begin, std::min(nz, begin + task_layers)};
}

std::optional<SlabTaskPlan> plan_slab_tasks(const Grid& grid, std::int64_t slab_layers, std::uint64_t task_bytes) {
  const std::int64_t nz = grid.dims.z;
  if (task_bytes == 0 || nz < 2) return std::nullopt;
  slab_layers = std::max<std::int64_t>(slab_layers, 1);
  const std::uint64_t layer = std::max<std::uint64_t>(bit_volume_bytes({grid.dims.x, grid.dims.y, 1}), 1);
  std::int64_t layers = std::max<std::int64_t>(static_cast<std::int64_t>(task_bytes / layer), 1);
  // Whole slabs a task when it holds one or more, so that its slabs are
  // the ones the whole job would stream.
  if (layers > slab_layers) layers = layers / slab_layers * slab_layers;
  layers = std::max(layers, (nz + kMaxSlabTasks - 1) / kMaxSlabTasks);
  const std::int64_t tasks = (nz + layers - 1) / layers;
  if (tasks < 2) return std::nullopt;
  return SlabTaskPlan{tasks, layers};
}

std::string slab_task_id(const std::string& job_id, std::int64_t index) {
  return job_id + std::string(kTaskMark) + std::to_string(index);
}

std::optional<SlabTaskRef> parse_slab_task_id(const std::string& id) {
  const std::size_t at = id.find(kTaskMark);
  if (at == std::string::npos || at == 0) return std::nullopt;
  SlabTaskRef ref{id.substr(0, at), 0};
  const char* first = id.data() + at + kTaskMark.size();
  const char* last = id.data() + id.size();
  const auto [end, ec] = std::from_chars(first, last, ref.index);
  if (ec != std::errc() || end != last || first == last || ref.index < 0) return std::nullopt;
  return ref;
}

}  // namespace voxd::server
