#pragma once
// What several analysis kinds share: replaying a streamed job's stored
// slabs, the model after skin removal, a section's layer, a radiograph's
// bytes, a distance field's values.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "server/jobs/analyses/job_analysis_kind.h"
#include "voxd/analysis/analysis_images.h"
#include "voxd/analysis/radiography.h"
#include "voxd/analysis/sdf_render.h"
#include "voxd/voxelize/slice_functions.h"
#include "voxd/voxelize/streamed.h"

namespace voxd::server {

std::string to_bytes(const std::vector<std::uint8_t>& v);

// The PNG text every image of a job carries ("voxd:job"), with the peel
// layers when peeled.
std::vector<PngText> image_text(const AnalysisInput& in, bool with_peel = false);

// The volume after r.peel layers of skin removal, or nullopt for none.
std::optional<BitVolume> peeled_volume(const api::AnalysisRequest& r, const BitVolume& volume);

// Replays a streamed job's stored volume slab by slab as its runs
// (voxd/run_slab.h), with progress over [from, to] of the bar (a request of
// two passes takes half each) and cancellation between slabs. The analyses
// then cost the stored runs, not the grid's voxels (at 8192^3: 137 MiB of
// runs, 50 GB of bits). Slabs hold up to kRunSlabRuns runs. The layers are
// decoded on every core (read_rle_run_slabs), the slabs handed on in order.
void replay_runs(const AnalysisInput& in, const RunSlabConsumer& consume, double from = 0.0, double to = 1.0);
// A slab of those runs as the memory estimates count it: kRunSlabRuns runs
// of 8 bytes and as many rows of 4, or fewer where the grid cannot hold so
// many (a row has at most (nx + 1) / 2 runs).
std::uint64_t run_slab_bytes(const Grid& grid);
// The same for a streamed job's stored values.
void replay_values(const AnalysisInput& in, const ValueSlabConsumer& consume);

// The section's layer index along its axis; throws AnalysisRejected for an
// index or coordinate outside the grid.
std::int64_t section_layer(const api::AnalysisRequest& r, const Grid& g);

// A radiograph's bytes in the request's format (PNG or its statistics).
std::string radiography_result(const AnalysisInput& in, const ThicknessImage& image);

// A distance field's values and how to read them (its convention and units
// come from the job's mode and options); nullopt for other jobs.
std::optional<SdfRenderInput> sdf_input(const AnalysisInput& in);

// The colours of a colour=slice request's slice function on the job's
// solid: its frame from the job's kept mesh, turned into the grid's frame
// as the job turned it, so they are the colours a slice job of the same
// upload and parameters gives its voxels. Throws AnalysisRejected for a job
// that kept no mesh or whose voxels are not cubes.
std::unique_ptr<const SliceColours> slice_colours(const AnalysisInput& in);

// Pixels of an image across `axis` of the grid.
std::uint64_t image_pixels(const Grid& grid, int axis);

// Images and reports beside the volumes, for the memory estimates.
inline constexpr std::uint64_t kImagesAndReports = std::uint64_t{16} << 20;

}  // namespace voxd::server
