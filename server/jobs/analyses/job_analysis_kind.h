#pragma once
// One kind of analysis as computed on a succeeded job (the request side is
// api/analyses/): how it is answered from the job's volumes in memory, how
// (and whether) from a streamed job's stored slabs, what it costs in memory
// and, when it needs the whole grid, what to tell a client refused it. Each
// kind lives in its own file under server/jobs/analyses/ and is listed once
// in job_analysis_kinds.cpp; server/jobs/job_analyses.cpp asks it, never its
// name (docs/architecture.md, "Adding an analysis").
#include <cstdint>
#include <string>

#include "api/analysis_request.h"
#include "server/jobs/job.h"
#include "server/jobs/job_analyses.h"
#include "voxd/bit_volume.h"
#include "voxd/grid.h"
#include "voxd/progress.h"

namespace voxd::server {

// What one request is answered from.
struct AnalysisInput {
  const api::AnalysisRequest& request;
  const JobSnapshot& job;
  const JobOutput& output;  // the volumes in memory, or a streamed job's stored files
  const ArtifactAccess& artifacts;
  JobControl* control = nullptr;
};

class JobAnalysisKind {
 public:
  virtual ~JobAnalysisKind() = default;
  virtual api::AnalysisKind kind() const = 0;

  // The bytes from the job's volumes in memory (`solid`, and the output's
  // values for the kinds that show them).
  virtual std::string compute(const AnalysisInput& in, const BitVolume& solid) const = 0;

  // Whether the request can be answered slab by slab from a stored RLE,
  // never holding the grid, with the bytes compute() gives.
  virtual bool streams_over_slabs(const api::AnalysisRequest&) const { return false; }
  // Whether it shows a value job's values where the job has them (a
  // distance field's section or preview): those are read whole.
  virtual bool shows_values(const api::AnalysisRequest&) const { return false; }
  // The bytes from a streamed job's stored slabs (streams_over_slabs).
  virtual std::string over_slabs(const AnalysisInput& in) const;
  // Bytes at peak answered over slabs, beside the replayed slab.
  virtual std::uint64_t over_slabs_memory(const api::AnalysisRequest&, const Grid&) const { return 0; }
  // Bytes a voxel at peak answered on the whole grid, beyond its bits.
  virtual std::uint64_t whole_grid_bytes_per_voxel(const api::AnalysisRequest& request) const = 0;
  // Bytes a triangle of the job's mesh at peak, for a kind that reads the
  // mesh (the thickness on the part); 0 for one that reads only volumes.
  virtual std::uint64_t bytes_per_triangle(const api::AnalysisRequest&) const { return 0; }
  // What needs the whole grid, in words: "a section coloured by wall
  // thickness" (whole_grid_refusal).
  virtual std::string needs_whole_grid(const api::AnalysisRequest& request) const = 0;
};

// The computing side of `kind` (job_analysis_kinds.cpp).
const JobAnalysisKind& job_analysis_kind(api::AnalysisKind kind);

}  // namespace voxd::server
