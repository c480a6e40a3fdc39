// Every analysis kind is one unit in two halves, each in its own registry
// (api/analyses/analysis_kinds.cpp, server/jobs/analyses/
// job_analysis_kinds.cpp): a kind named in kAnalysisKindNames and forgotten
// in either fails here rather than at a client's first request.
#include <gtest/gtest.h>

#include <algorithm>
#include <span>
#include <string>

#include "api/analyses/analysis_kind.h"
#include "api/analysis_request.h"
#include "api/job_params.h"
#include "server/jobs/analyses/job_analysis_kind.h"
#include "server/jobs/job_analyses.h"
#include "server/jobs/analyses/analysis_support.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/volume_format.h"

namespace voxd::test {
namespace {

// A URL query's fields as the route reads them ("%2B" is '+').
api::Fields query_fields(const std::string& query) {
  api::Fields fields;
  std::size_t at = 0;
  while (at < query.size()) {
    const std::size_t amp = std::min(query.find('&', at), query.size());
    const std::string pair = query.substr(at, amp - at);
    const std::size_t eq = pair.find('=');
    std::string value = pair.substr(eq + 1);
    if (value.starts_with("%2B")) value.replace(0, 3, "+");
    fields.emplace_back(pair.substr(0, eq), value);
    at = amp + 1;
  }
  return fields;
}

TEST(AnalysisKinds, EveryNamedKindHasBothHalvesAndItsQueryReadsBackToItsKey) {
  for (const auto& [kind, name] : api::kAnalysisKindNames) {
    SCOPED_TRACE(name);
    EXPECT_EQ(api::analysis_kind_request(kind).kind(), kind);
    EXPECT_EQ(server::job_analysis_kind(kind).kind(), kind);
    // The defaults (a section needs its layer), written as the canonical
    // query, are a request of their own with the same key: the URL a job's
    // status gives finds the result the worker kept.
    const api::Fields given = kind == api::AnalysisKind::section ? api::Fields{{"index", "3"}} : api::Fields{};
    const api::AnalysisRequest r = api::parse_analysis_request(kind, given, "");
    const api::AnalysisRequest again = api::parse_analysis_request(kind, query_fields(r.query()), "");
    EXPECT_EQ(again.artifact_key(), r.artifact_key());
    EXPECT_EQ(api::to_json(again), api::to_json(r));
    EXPECT_EQ(api::to_json(r).at("kind"), name);
  }
}

// The thickness on the part reads the job's mesh: its memory grows with the
// triangles, on top of the thickness volume's; a volume format's does not.
// And its thresholds go into its key and come back from its query.
TEST(AnalysisKinds, TheThicknessOnThePartCountsTheMeshAndKeysItsThresholds) {
  const Grid grid{{0, 0, 0}, 1.0, {64, 64, 64}};
  const api::JobParams params = api::parse_job_params(nlohmann::json::object());
  const auto on_part = api::parse_analysis_request(api::AnalysisKind::thickness, {{"format", "glb"}, {"min_wall", "0.8"}}, "");
  const auto volume = api::parse_analysis_request(api::AnalysisKind::thickness, {{"format", "nrrd"}}, "");
  const std::uint64_t volume_bytes = server::analysis_memory_on_job(volume, params, grid, false, 1ull << 40, 1'100'000);
  EXPECT_EQ(volume_bytes, server::analysis_memory_on_job(volume, params, grid, false, 1ull << 40, 0));
  EXPECT_EQ(server::analysis_memory_on_job(on_part, params, grid, false, 1ull << 40, 1'100'000),
            volume_bytes + 256ull * 1'100'000);
  const api::AnalysisRequest again = api::parse_analysis_request(api::AnalysisKind::thickness, query_fields(on_part.query()), "");
  EXPECT_EQ(again.min_wall, 0.8);
  EXPECT_EQ(again.artifact_key(), on_part.artifact_key());
  EXPECT_NE(on_part.artifact_key(),
            api::parse_analysis_request(api::AnalysisKind::thickness, {{"format", "glb"}, {"min_wall", "0.9"}}, "").artifact_key());
}

// A streamed analysis's estimate counts a slab of stored runs at most
// run_slab_bytes: read back from the RLE of the grid with the most runs a
// row can hold (every other voxel), the slab is exactly that, and a grid
// too large for one slab is held to kRunSlabRuns runs and rows.
TEST(AnalysisKinds, ARunSlabIsAtMostWhatTheEstimatesCount) {
  Grid g;
  g.dims = {41, 12, 9};
  BitVolume checker(g);
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; i += 2) checker.set(i, j, k, true);
  VectorSink sink;
  write_rle(checker, sink);
  std::uint64_t largest = 0;
  read_rle_run_slabs(std::span<const std::uint8_t>(sink.data), g.dims.z, [&](std::int64_t, const RunSlab& slab) {
    largest = std::max<std::uint64_t>(largest, 8 * slab.run_count() + 4 * static_cast<std::uint64_t>(slab.row_count()));
  });
  EXPECT_EQ(largest, 8 * 21 * 12 * 9 + 4 * 12 * 9);
  EXPECT_EQ(server::run_slab_bytes(g), largest);
  Grid huge;
  huge.dims = {8194, 7918, 6203};
  EXPECT_EQ(server::run_slab_bytes(huge), 12 * kRunSlabRuns);
}

}  // namespace
}  // namespace voxd::test
