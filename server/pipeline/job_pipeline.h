#pragma once
// One voxelization job from uploaded bytes to a volume: decode, (report),
// rotate/orient, resolve the grid, check limits, voxelize. Shared by the CLI
// and the service's workers so both produce byte-identical results.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/mat3x3.hpp>
#include <nlohmann/json.hpp>

#include "api/inside_choice.h"
#include "api/job_params.h"
#include "api/job_warning.h"
#include "api/job_volumes.h"
#include "voxd/bit_volume.h"
#include "voxd/analysis/mass_properties.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/mesh_report.h"
#include "voxd/progress.h"
#include "voxd/run_slab.h"
#include "voxd/encode/volume_format.h"
#include "voxd/enum_names.h"
#include "voxd/voxelize/streamed.h"

namespace voxd {

// Voxels per z-slab of a streamed job: about this many bytes of bits.
inline constexpr std::uint64_t kStreamSlabBytes = std::uint64_t{128} << 20;

// Where a job's volume goes, as far as how the job runs is concerned
// (plan_execution). The defaults are the service's stored result: an RLE
// that takes slabs and runs, the volume kept whole when made in memory (it
// is cached and analysed).
struct JobOutputKind {
  // Why the output cannot take the volume slab by slab (a format that needs
  // the whole volume, a mode that writes the format itself); none when it can.
  std::optional<std::string> no_slabs;
  // An RLE of bits: a job whose mode makes runs is written from them.
  bool takes_runs = true;
  // The volume made in memory is kept whole (so runs only when streamed).
  bool keeps_volume = true;
};

// How a job runs, decided in one place (plan_execution) for the CLI, the
// service's workers and the slab tasks a replicated service splits a job
// into (which make a range of layers of a job planned as runs).
enum class ExecutionPath {
  memory,  // whole in memory: execute_voxel_job
  slabs,   // slab by slab to a consumer: execute_streamed_voxel_job
  runs,    // its bits as runs, never a dense volume: execute_voxel_runs_job
};
inline constexpr EnumNames<ExecutionPath, 3> kExecutionPathNames{
    {{ExecutionPath::memory, "memory"}, {ExecutionPath::slabs, "slabs"}, {ExecutionPath::runs, "runs"}}};
inline const char* to_string(ExecutionPath path) noexcept { return name_of(kExecutionPathNames, path); }

struct JobLimits {
  DecodeLimits decode;
  JobOutputKind output;
  std::uint64_t max_voxels = std::uint64_t{1} << 33;  // a grid made whole in memory: 8 Gi voxels = 1 GiB of bits
  // A grid made slab by slab: memory does not bound it (one slab at a time),
  // so this bounds its time and disk; 2^40 voxels is past 10000^3.
  std::uint64_t max_streamed_voxels = std::uint64_t{1} << 40;
  // Jobs that can stream (api::JobParams::streaming auto) do when their
  // volumes in memory would take more than this: 512 MiB is a 2^32-voxel grid
  // of bits, past which streaming is as fast as memory and far smaller.
  // 0: never (POST /v1/voxelize answers from memory).
  std::uint64_t stream_above_bytes = std::uint64_t{512} << 20;
  // About this many bytes of bits per slab of a streamed job.
  std::uint64_t stream_slab_bytes = kStreamSlabBytes;
  // The job welds its mesh anyway (it keeps it, and reports on it): "auto"
  // then counts the edges of the welded mesh, exactly and once, rather
  // than hashing them in parallel (the choice for a job that never welds).
  bool welds_mesh = false;
  // Where a job that names no "device" runs what a GPU can (voxd serve
  // --device, voxd voxelize --device; voxd/compute_device.h).
  ComputeDevice device = ComputeDevice::automatic;
};

struct StageTimings {
  std::vector<std::pair<std::string, double>> stages;  // in order, seconds
  void add(std::string name, double seconds) { stages.emplace_back(std::move(name), seconds); }
  double total() const;
};

// A job after its cheap, synchronous part: decoded, rotated, grid resolved and
// checked against the limits. The service does this at submission, so a bad
// upload or an oversized grid is refused at once with a clear error, and
// workers receive only jobs that fit.
struct PreparedVoxelJob {
  api::JobParams params;
  Mesh mesh;  // as uploaded; execute_voxel_job rotates it
  // weld_vertices(mesh), when it was made (for "auto" with
  // JobLimits::welds_mesh, or for the kept mesh): the kept mesh and the mesh
  // report read it rather than welding again; and its edge topology when
  // that was counted, which the report reads too.
  std::shared_ptr<const Mesh> welded;
  std::optional<EdgeTopology> welded_topology;
  MeshFormat format = MeshFormat::unknown;
  DecodeWarnings decode_warnings;  // for the mesh report
  std::uint64_t triangles = 0;
  glm::dmat3 rotation{1.0};  // applied before voxelization (rotation, then orient)
  Grid grid;
  // Made slab by slab (execute_streamed_voxel_job), as decided from the
  // job's streaming and its memory; memory_estimate is then the streamed one.
  bool streamed = false;
  ExecutionPath path = ExecutionPath::memory;  // how it runs (plan_execution)
  std::int64_t slab_layers = 0;  // z layers per slab when streamed
  std::uint64_t memory_estimate = 0;  // bytes at peak the way it runs, for admission control
  StageTimings timings;
  // The inside test, resolved ("auto" chooses from the mesh: params.inside
  // is then set to it), what orienting the mesh turned round (when the test
  // needs outward triangles), and what preparing found doubtful.
  api::InsideChoice inside;
  std::optional<OrientationRepair> orientation;
  std::vector<api::JobWarning> warnings;
};

struct VoxelJobResult {
  MeshFormat format = MeshFormat::unknown;
  std::uint64_t triangles = 0;
  std::optional<MeshReport> report;  // when requested: it costs a weld
  std::optional<MassProperties> mesh_mass;  // with the report; in the voxels' (rotated) frame
  glm::dmat3 rotation{1.0};
  Grid grid;
  // What the mode made, as the store keeps it (api/job_volumes.h): the
  // solid is never null in memory (the mode's bits or the parity solid);
  // made slab by slab and handed on (execute_streamed_voxel_job), only
  // values_info is set and `filled` is counted from the slabs.
  api::JobVolumes volumes;
  std::uint64_t filled = 0;
  bool streamed = false;
  StageTimings timings;
  api::InsideChoice inside;
  // The prepared job's warnings, then the run's (an empty result, an open
  // mesh under parity seen by the report).
  std::vector<api::JobWarning> warnings;
};

// Bytes the job's volumes will take at peak, for admission control.
std::uint64_t estimate_job_memory(const Grid& grid, const api::JobParams& params);
// The same for the job made slab by slab: one slab of `slab_layers`, the
// triangles binned by slab and the encoder's buffers (the mesh apart).
// Measured: 269 MiB peak RSS for the 1.1M-triangle bunny at 8192^3 with
// its mesh and 128 MiB slabs (docs/benchmarks.md, issue #14).
// `layer_bytes`: what one layer of a slab takes (api::JobMode::
// streamed_layer_bytes), 0 for a layer of bits.
std::uint64_t estimate_streamed_job_memory(const Grid& grid, std::int64_t slab_layers, std::uint64_t triangles,
                                           std::uint64_t layer_bytes = 0);
// Z layers per slab of a streamed job for about `slab_bytes` at once.
std::int64_t streamed_job_slab_layers(const Grid& grid, const api::JobParams& params, std::uint64_t slab_bytes);

// Bytes decoding an upload takes at its peak beside the upload itself (the
// mesh, the weld's tables), from its size and format; for Draco, the
// isolated decoder's process. Checked against measured peaks in
// tests/service/memory_estimate_test.cpp.
std::uint64_t decode_memory_estimate(std::span<const std::uint8_t> mesh_bytes, std::string_view name_hint,
                                     const DecodeLimits& limits);
// The same for an upload of `bytes` whose format was detected already.
std::uint64_t decode_memory_estimate(std::uint64_t bytes, MeshFormat format, const DecodeLimits& limits);
// The memory the isolated Draco decoder is given for a file of `bytes`
// (at most the service's --max-decode-memory).
std::uint64_t draco_child_memory(std::uint64_t bytes);
// Bytes a decoded mesh holds.
std::uint64_t mesh_memory(const Mesh& mesh);
// The prepared job's mesh, and its welded copy when it holds one.
std::uint64_t prepared_mesh_memory(const PreparedVoxelJob& job);

struct ExecutionPlan {
  ExecutionPath path = ExecutionPath::memory;
  bool streamed = false;  // slab by slab (the slabs or runs path, not the whole grid at once)
  // Why it cannot stream (the mode, or the output); none when it can.
  std::optional<std::string> no_slabs;
};
// How a job on `grid` runs: streamed when its params ask for it (streaming
// on), or, streaming auto, when the mode and the output can take slabs and
// the mode is faster so (JobMode::faster_in_slabs) or its volumes would take
// more than limits.stream_above_bytes (0: never); as runs when the output
// takes them and the mode makes them (streamed, or when the volume is not
// kept whole); else slabs or memory. Throws Error(invalid_argument) for
// streaming on that cannot be.
ExecutionPlan plan_execution(const api::JobParams& params, const Grid& grid, const JobLimits& limits);

// Decode, rotate/orient, resolve the grid, check limits, plan how it runs
// (plan_execution). Throws voxd::Error.
PreparedVoxelJob prepare_voxel_job(std::span<const std::uint8_t> mesh_bytes, std::string_view name_hint,
                                   const api::JobParams& params, const JobLimits& limits);
// The same for an upload whose format the caller detected already
// (detect_mesh_format(mesh_bytes, name_hint), to size decoding's memory
// first): the format is detected once per upload.
PreparedVoxelJob prepare_voxel_job(MeshFormat detected, std::span<const std::uint8_t> mesh_bytes,
                                   std::string_view name_hint, const api::JobParams& params, const JobLimits& limits);

// The expensive part: (mesh report of the mesh as uploaded,) rotation,
// voxelization, count.
VoxelJobResult execute_voxel_job(PreparedVoxelJob job, bool with_report, JobControl* control, int threads = 0);

// The same, slab by slab (voxd/voxelize/streamed.h): each finished z-slab of
// the job's bits goes to `consume` (an encoder, a file) and is gone after;
// memory is the mesh and one slab of `slab_layers` z layers. A job of
// values hands its values' slabs to `values` as well (its bits, the solid,
// still go to `consume`). Throws Error(invalid_argument) for a job that does
// not stream (api::JobMode::streaming_refusal).
VoxelJobResult execute_streamed_voxel_job(PreparedVoxelJob job, bool with_report, JobControl* control, int threads,
                                          std::int64_t slab_layers, const BitSlabConsumer& consume,
                                          const ValueSlabConsumer& values = {});

// A job of bits whose output is made of runs (the RLE): its bits as runs
// (voxd/voxelize/runs.h), slab by slab to `consume`, bit for bit those the
// other paths make, without a dense volume; `filled` counts them, `streamed`
// is the job's. Throws Error(invalid_argument) for a job whose mode does not
// make runs (api::JobMode::makes_runs). `prepare`: the consumer's work on
// each slab that can run where the slab is made, in parallel (a writer's
// preparer(): its encoding).
VoxelJobResult execute_voxel_runs_job(PreparedVoxelJob job, bool with_report, JobControl* control, int threads,
                                      const RunSlabConsumer& consume, const RunSlabPreparer& prepare = {});

// One part of a job spread over many workers (server/jobs/slab_tasks.h):
// only the z layers `range` of its bits, as runs to `consume`, bit for bit
// those of the whole job; `filled` counts them. No mesh report
// (describe_voxel_job gives it). Throws Error(invalid_argument) for a job
// whose mode does not make runs (api::JobMode::makes_runs).
VoxelJobResult execute_voxel_layers(PreparedVoxelJob job, LayerRange range, JobControl* control, int threads,
                                    const RunSlabConsumer& consume, const RunSlabPreparer& prepare = {});

// What a job's result says beside its voxels, without making them: the mesh
// report, the rotation, the mass properties in the voxels' frame (for the
// worker that puts a job spread over workers together).
VoxelJobResult describe_voxel_job(PreparedVoxelJob job);

// Throws Error(limit_exceeded) for a grid of more than `max_voxels` voxels;
// `hint` completes the advice.
void check_voxel_limit(const Grid& grid, std::uint64_t max_voxels, std::string_view hint);

// Both steps, as the CLI runs them.
VoxelJobResult run_voxel_job(std::span<const std::uint8_t> mesh_bytes, std::string_view name_hint,
                             const api::JobParams& params, const JobLimits& limits, bool with_report,
                             JobControl* control, int threads = 0);

}  // namespace voxd
