#pragma once
// The analyses of a succeeded job (api/analysis_request.h) as the bytes their
// routes serve. The same functions run in the worker, for the analyses a job
// JSON asks for up front, and in the HTTP routes, for the ones asked later,
// and both keep the result under the request's artifact key, so a client
// gets identical bytes either way.
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "api/analysis_request.h"
#include "server/jobs/background_save.h"
#include "server/jobs/job.h"
#include "voxd/analysis/analysis_images.h"
#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"
#include "voxd/progress.h"

namespace voxd::server {

class JobManager;  // server/jobs/job_manager.h
class JobStore;    // server/jobs/job_store.h

// Where a job's kept results live (the job store's artifacts folder).
// `scope` names the job: requests for the same key of the same scope are
// computed once at a time (a second one waits and answers the kept result),
// so a front end asking for a preview, a section and the thickness volume at
// once does not run three local-thickness computations side by side.
struct ArtifactAccess {
  std::string scope;
  std::function<std::optional<std::string>(const std::string& key)> load;
  std::function<void(const std::string& key, std::string_view bytes)> save;
  // The job's wall-thickness map when the caller already holds it (the
  // CLI): used as it is, neither loaded nor copied.
  std::shared_ptr<const DenseVolume<float>> wall_map = nullptr;
  // Reads an artifact of exactly out.size() bytes into `out` (false if
  // there is none of that size); when not given, `load` and a copy.
  std::function<bool(const std::string& key, std::span<char> out)> load_into = nullptr;
};
ArtifactAccess artifacts_of(JobManager& jobs, const std::string& id);

// A request this job cannot answer (a section index beyond the grid): the
// message says what is accepted. HTTP answers 400; a job's analyses entry
// says "failed" with the message.
class AnalysisRejected : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct AnalysisResult {
  std::string bytes;
  bool kept = false;  // answered from the kept artifact
};

// The result, from the kept artifact when there is one, else computed, kept
// and returned. The measurements (analysis, radiography, thickness) are of
// the job's solid; a value job's section shows its values, and a distance
// field's preview renders its zero level set. `control` (may be null)
// carries progress and cancellation.
AnalysisResult job_analysis(const api::AnalysisRequest& request, const JobSnapshot& job, const JobOutput& output,
                            const ArtifactAccess& artifacts, JobControl* control = nullptr);

// A result as a route sends it: a large one computed just now (from
// `keep_while_sent_from` bytes) is kept while it is sent, by `keeping`, which
// the answer holds until it has been sent (its write holds the request's key
// until it ends: a second request waits, then reads the kept result).
struct AnalysisAnswer {
  std::shared_ptr<std::string> bytes;
  bool kept = false;  // answered from the kept artifact
  std::shared_ptr<BackgroundSave> keeping;
};
AnalysisAnswer job_analysis_answer(const api::AnalysisRequest& request, const JobSnapshot& job,
                                   const JobOutput& output, const ArtifactAccess& artifacts,
                                   std::size_t keep_while_sent_from, JobControl* control = nullptr);

// Bytes a request may take at its peak, beyond the job's volumes, for the
// memory budget. Measured (docs/security.md): local thickness and the
// analysis that uses it about 14 bytes a voxel at 256^3, the thickness
// volume route about 23; wall thickness is in the same range (the feature
// transform's 4 bytes a voxel and the float map, bits, and the leftovers of
// its painting); the factors below hold a margin over those.
// `over_slabs`: answered slab by slab (streams_over_slabs on a streamed
// job): its images and one slab, whatever the grid.
std::uint64_t estimate_analysis_memory(const api::AnalysisRequest& request, const Grid& grid, bool over_slabs = false);

// Whether a request can be answered slab by slab from a stored RLE, never
// holding the grid: radiography and sections without peel or thickness
// colours, and the analysis without thickness, skin or clean-up. The others
// need the whole grid in memory.
bool streams_over_slabs(const api::AnalysisRequest& request);
// The same on a job of `params`: a distance field's preview and sections
// show its values, read whole.
bool streams_over_slabs(const api::AnalysisRequest& request, const api::JobParams& params);

// Bytes a request that needs the whole grid takes on it: the grid's bits
// and the request's own.
std::uint64_t whole_grid_memory(const api::AnalysisRequest& request, const Grid& grid);

// The refusal (HTTP 422) of a request that needs the whole grid on a grid
// over `max_job_memory`: what needs it, the largest grid accepted, and what
// streams instead.
std::string whole_grid_refusal(const api::AnalysisRequest& request, const Grid& grid, std::uint64_t max_job_memory);

// Bytes a request takes on a job, for the memory budget: on a streamed job
// a request that does not stream loads the grid too, and one over
// `max_job_memory` throws Error(limit_exceeded) with whole_grid_refusal. A
// request that reads the job's mesh adds its `triangles`' share.
std::uint64_t analysis_memory_on_job(const api::AnalysisRequest& request, const api::JobParams& params, const Grid& grid,
                                     bool streamed_job, std::uint64_t max_job_memory, std::uint64_t triangles = 0);

// The volumes a request on a succeeded job is answered from, read from
// `store`: the stored RLE of a streamed job when the request streams over
// it, else the volume and values whole.
JobOutput analysis_output(const api::AnalysisRequest& request, const JobSnapshot& job, const JobStore& store);

// What one pixel value of a radiograph asked for by `request` means.
PngScale radiography_scale(const api::AnalysisRequest& request, const Grid& grid);

// The status entries of a job's requested analyses, all in `state`:
// {"request", "state", "error"} (the service adds each one's "url").
nlohmann::json analyses_status(const std::vector<api::AnalysisRequest>& requests, const char* state);

// The artifact key a job's thickness map of `measure` is kept under.
const char* thickness_map_key(api::ThicknessMeasure measure);

// A job's thickness map, and its keeping: a map just computed is written to
// the store while the caller goes on with it, and waited for when this goes
// (server/jobs/background_save.h). Hold it, on the thread that asked for
// it, for as long as the map is used.
struct JobThicknessMap {
  std::shared_ptr<const DenseVolume<float>> map;
  BackgroundSave keeping;
  const DenseVolume<float>& operator*() const { return *map; }
  const DenseVolume<float>* operator->() const { return map.get(); }
};

// The job's thickness map (voxels) of `measure`, computed once and kept: the
// wall thickness for the report, sections and previews.
JobThicknessMap job_thickness_map(const BitVolume& volume, const ArtifactAccess& artifacts, JobControl* control,
                                  api::ThicknessMeasure measure = api::ThicknessMeasure::wall);

}  // namespace voxd::server
