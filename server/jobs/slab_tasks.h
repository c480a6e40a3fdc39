#pragma once
// One huge job spread over many workers (replicas on one shared backend,
// docs/scale-out.md): its grid, made slab by slab anyway (voxd/voxelize/
// streamed.h), is cut into ranges of z layers, each a task on the shared
// queue that any replica's worker makes alone and stores as its RLE layer
// blocks. The worker that finishes the last task puts the job's RLE
// together (the head, every task's blocks in z order, the tail: the stream
// is one block per layer, so that is the whole job's bytes) and ends the
// job. A replica killed during a task loses only that task: its lease
// lapses and another replica redoes it, as with any job.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "voxd/byte_sink.h"
#include "voxd/grid.h"
#include "voxd/voxelize/streamed.h"

namespace voxd::server {

struct SlabTaskPlan {
  std::int64_t tasks = 0;
  std::int64_t task_layers = 0;  // z layers per task, the last task's fewer
  // The z layers task `index` makes on a grid of `nz` layers.
  LayerRange range(std::int64_t index, std::int64_t nz) const;
};

// More tasks than this are fewer, larger ones: a task's fixed cost (decode,
// triangle bins) stays small beside its voxels.
inline constexpr std::int64_t kMaxSlabTasks = 1024;

// The tasks a streamed job on `grid` of `slab_layers` layers a slab splits
// into, about `task_bytes` of bits each (whole slabs when that is one or
// more); nullopt when it is one task (or task_bytes is 0: no splitting).
std::optional<SlabTaskPlan> plan_slab_tasks(const Grid& grid, std::int64_t slab_layers, std::uint64_t task_bytes);

// The queue's id of a job's task, and back (nullopt: a job, not a task).
std::string slab_task_id(const std::string& job_id, std::int64_t index);
struct SlabTaskRef {
  std::string job_id;
  std::int64_t index = 0;
};
std::optional<SlabTaskRef> parse_slab_task_id(const std::string& id);

// What the shared backend keeps of a split job: its plan, each task's
// stored blocks and voxel count. All of it goes with the job (deleted or
// expired with it) and is dropped once the job has ended.
class SharedSlabTasks {
 public:
  virtual ~SharedSlabTasks() = default;

  // Kept with the job's record, before its tasks are queued (JobQueue::split).
  virtual void save_plan(const std::string& id, const SlabTaskPlan& plan) const = 0;
  struct State {
    SlabTaskPlan plan;
    bool cancel_requested = false;  // a client asked for the job's cancellation
  };
  // nullopt when the job is gone or was never split.
  virtual std::optional<State> state(const std::string& id) const = 0;

  // Whether task `index` is done (its blocks stored and counted).
  virtual bool task_done(const std::string& id, std::int64_t index) const = 0;
  // Stores a task's RLE blocks through `write`, once: a task made twice
  // keeps the first copy. Throws StorageFull past the backend's memory.
  virtual void write_blocks(const std::string& id, std::int64_t index,
                            const std::function<void(ByteSink&)>& write) const = 0;
  // Copies a task's stored blocks into `sink`; false when they are gone.
  virtual bool read_blocks(const std::string& id, std::int64_t index, ByteSink& sink) const = 0;
  // Counts task `index` done with `filled` voxels (a task counted already
  // keeps its first count) and moves the job's progress on. Returns how
  // many of its tasks are done; 0 when the job is no longer running.
  virtual std::int64_t finish_task(const std::string& id, std::int64_t index, std::uint64_t filled,
                                   std::int64_t tasks) const = 0;
  // The voxels of every task counted done.
  virtual std::uint64_t filled(const std::string& id) const = 0;
  // Drops the plan's blocks and counts (after the job has ended).
  virtual void drop_tasks(const std::string& id) const = 0;
};

}  // namespace voxd::server
