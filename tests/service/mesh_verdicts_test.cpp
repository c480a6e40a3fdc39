// Jobs on the meshes people really have (issue #36), through the pipeline
// every job takes (prepare_voxel_job, execute_voxel_job) with the job JSON's
// defaults: open parts (CAD parts with holes punched in them, and open files
// of Debian's assimp-testmodels), parts written inside out, parts in metres.
// The references are independent of the inside tests under test: the same
// part closed, the part's bounding box and the grid's border, and the closed
// form of each part's volume.
#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/job_params.h"
#include "server/pipeline/job_pipeline.h"
#include "support/assimp_models.h"
#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "voxd/analysis/analysis.h"

namespace voxd {
namespace {

using nlohmann::json;

VoxelJobResult run(const Mesh& mesh, const json& params, bool with_report = true) {
  JobLimits limits;
  return run_voxel_job(test::to_binary_stl(mesh), "part.stl", api::parse_job_params(params), limits, with_report, nullptr, 0);
}

VoxelJobResult run_file(const std::string& path, const json& params) {
  return run_voxel_job(test::read_file(path), path, api::parse_job_params(params), JobLimits{}, true, nullptr, 0);
}

bool has_warning(const VoxelJobResult& r, const std::string& code) {
  return std::any_of(r.warnings.begin(), r.warnings.end(), [&](const api::JobWarning& w) { return w.code == code; });
}

// Filled voxels on the grid's outermost layers, and filled voxels whose
// centre lies outside `box` by more than a voxel (a streak leaves the part).
struct Leaks {
  std::uint64_t on_border = 0, outside_box = 0;
};

Leaks leaks_of(const BitVolume& v, const Aabb& box) {
  const Grid& g = v.grid();
  Leaks out;
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) {
        if (!v.get(i, j, k)) continue;
        if (i == 0 || j == 0 || k == 0 || i == g.dims.x - 1 || j == g.dims.y - 1 || k == g.dims.z - 1) ++out.on_border;
        const glm::dvec3 c = g.center(i, j, k);
        const double h = g.voxel_size;
        if (c.x < box.min.x - h || c.y < box.min.y - h || c.z < box.min.z - h || c.x > box.max.x + h ||
            c.y > box.max.y + h || c.z > box.max.z + h)
          ++out.outside_box;
      }
  return out;
}

const json kDefaults = {{"grid", {{"resolution", 96}, {"padding", 2}}}};

double relative(double a, double b) { return std::abs(a - b) / b; }

class OpenPart : public testing::TestWithParam<std::string> {};

TEST_P(OpenPart, DefaultsFillThePartWithinOnePercentOfItClosedAndNothingOutsideIt) {
  const test::Part part = test::part_named(GetParam());
  const VoxelJobResult closed = run(part.mesh, kDefaults);
  EXPECT_EQ(closed.inside.test, InsideTest::parity);
  EXPECT_TRUE(closed.inside.automatic);
  EXPECT_TRUE(closed.warnings.empty()) << api::to_json(closed.warnings).dump();
  // The closed part's voxels are its volume (the closed form) within half a
  // voxel across its surface: the reference the open part is held to is sound.
  const double h = closed.grid.voxel_size;
  EXPECT_LT(std::abs(static_cast<double>(closed.filled) * h * h * h - part.volume), 0.5 * part.surface_area * h);

  const Mesh open = test::punched(part.mesh, 41);
  const VoxelJobResult holes = run(open, kDefaults);
  ASSERT_EQ(holes.grid.dims, closed.grid.dims);
  EXPECT_EQ(holes.inside.test, InsideTest::winding);
  EXPECT_TRUE(holes.inside.automatic);
  EXPECT_NE(holes.inside.reason.find("boundary edges"), std::string::npos) << holes.inside.reason;
  EXPECT_LT(relative(static_cast<double>(holes.filled), static_cast<double>(closed.filled)), 0.01)
      << holes.filled << " voxels open, " << closed.filled << " closed";
  const Leaks leaks = leaks_of(*holes.volumes.solid, bounds(part.mesh));
  EXPECT_EQ(leaks.on_border, 0u);
  EXPECT_EQ(leaks.outside_box, 0u);
  EXPECT_FALSE(has_warning(holes, "open-mesh-parity"));
  // The same wall-thickness verdicts, with min_wall well under the part's
  // thinnest wall and well over it.
  if (part.thinnest_wall > 0) {
    for (double min_wall : {part.thinnest_wall / 2, part.thinnest_wall * 2}) {
      AnalysisOptions o;
      o.skin = false;
      o.min_wall_voxels = min_wall / h;
      const ThicknessVerdict closed_verdict = thickness_verdict(*analyze_volume(*closed.volumes.solid, o).thickness);
      EXPECT_EQ(thickness_verdict(*analyze_volume(*holes.volumes.solid, o).thickness), closed_verdict) << min_wall;
      EXPECT_EQ(closed_verdict, min_wall < part.thinnest_wall ? ThicknessVerdict::pass : ThicknessVerdict::fail) << min_wall;
    }
  }

  // Parity, asked for by name, leaks through the same holes, and is warned
  // about: what the default no longer does.
  json parity = kDefaults;
  parity["inside"] = "parity";
  const VoxelJobResult streaks = run(open, parity);
  EXPECT_GT(leaks_of(*streaks.volumes.solid, bounds(part.mesh)).on_border, 0u);
  EXPECT_TRUE(has_warning(streaks, "open-mesh-parity")) << api::to_json(streaks.warnings).dump();
}

TEST_P(OpenPart, InsideOutClosedOrOpenFillsAsTheRightWayRoundWithAWarning) {
  const test::Part part = test::part_named(GetParam());
  const VoxelJobResult outward = run(part.mesh, kDefaults);
  for (const Mesh& inverted : {test::flipped(part.mesh), test::flipped(test::punched(part.mesh, 41))}) {
    const VoxelJobResult r = run(inverted, kDefaults);
    EXPECT_LT(relative(static_cast<double>(r.filled), static_cast<double>(outward.filled)), 0.01)
        << r.filled << " voxels inside out, " << outward.filled << " outward";
    EXPECT_TRUE(has_warning(r, "mesh-inverted")) << api::to_json(r.warnings).dump();
    ASSERT_TRUE(r.report && r.report->orientation);
    EXPECT_EQ(r.report->orientation->inverted_components, 1u);
    EXPECT_GT(r.report->volume, 0.0);  // the report's mesh is the oriented one
  }
  // The winding number asked for by name is oriented too: an inside-out
  // open part no longer comes back empty.
  json winding = kDefaults;
  winding["inside"] = "winding";
  const VoxelJobResult r = run(test::flipped(test::punched(part.mesh, 41)), winding);
  EXPECT_LT(relative(static_cast<double>(r.filled), static_cast<double>(outward.filled)), 0.01);
}

INSTANTIATE_TEST_SUITE_P(CadParts, OpenPart,
                         testing::Values("hex_nut.stl", "flanged_bushing.stl", "torus.stl", "blob.stl"),
                         [](const auto& info) {
                           std::string name = info.param.substr(0, info.param.find('.'));
                           return name;
                         });

// Open files nobody here made: a sphere with a hole, a scanned figure and
// an open, partly inconsistent spider.
class OpenFile : public testing::TestWithParam<std::string> {};

TEST_P(OpenFile, DefaultsLeaveNoStreakAndNothingOutsideThePart) {
  const std::string path = test::assimp_model(GetParam());
  const VoxelJobResult r = run_file(path, kDefaults);
  ASSERT_TRUE(r.report);
  ASSERT_GT(r.report->boundary_edges, 0u);
  EXPECT_EQ(r.inside.test, InsideTest::winding);
  EXPECT_GT(r.filled, 0u);
  const Leaks leaks = leaks_of(*r.volumes.solid, r.report->bbox);
  EXPECT_EQ(leaks.on_border, 0u);
  EXPECT_EQ(leaks.outside_box, 0u);
}

INSTANTIATE_TEST_SUITE_P(AssimpTestModels, OpenFile,
                         testing::Values("STL/sphereWithHole.stl", "STL/Spider_binary.stl", "STL/Wuson.stl"),
                         [](const auto& info) {
                           std::string name = info.param.substr(info.param.find('/') + 1);
                           return name.substr(0, name.find('.'));
                         });

TEST(OpenFile, ASphereWithAHoleFillsTheSphere) {
  // sphereWithHole.stl: a sphere of radius 1.5 about (1.5, 1.5, 1.5) missing
  // a few triangles. Its voxels are the sphere's volume within the
  // facets' and the voxels' error.
  const VoxelJobResult r = run_file(test::assimp_model("STL/sphereWithHole.stl"), kDefaults);
  const double sphere = 4.0 / 3.0 * 3.14159265358979 * 1.5 * 1.5 * 1.5;
  EXPECT_LT(relative(static_cast<double>(r.filled) * r.grid.voxel_volume(), sphere), 0.05);
}

TEST(Units, APartInMetresGivesTheSameJobInMillimetres) {
  const test::Part part = test::part_named("flanged_bushing.stl");
  Mesh metres = part.mesh;
  for (glm::vec3& v : metres.vertices) v = glm::vec3(glm::dvec3(v) / 1000.0);
  const json mm_params = {{"grid", {{"voxel_size", 0.1}, {"padding", 1}}}};
  json m_params = mm_params;
  m_params["units"] = "m";
  const VoxelJobResult mm = run(part.mesh, mm_params), m = run(metres, m_params);
  auto same6 = [](double a, double b) { return std::abs(a - b) <= 5e-6 * std::max(std::abs(a), std::abs(b)) + 1e-9; };
  ASSERT_TRUE(mm.report && m.report);
  for (int a = 0; a < 3; ++a) {
    EXPECT_TRUE(same6(m.report->bbox.min[a], mm.report->bbox.min[a])) << m.report->bbox.min[a] << " " << mm.report->bbox.min[a];
    EXPECT_TRUE(same6(m.report->bbox.max[a], mm.report->bbox.max[a]));
    EXPECT_TRUE(same6(m.grid.origin[a], mm.grid.origin[a]));
  }
  EXPECT_EQ(m.grid.dims, mm.grid.dims);
  EXPECT_EQ(m.grid.voxel_size, mm.grid.voxel_size);
  EXPECT_TRUE(same6(m.report->surface_area, mm.report->surface_area));
  EXPECT_TRUE(same6(m.report->volume, mm.report->volume));
  EXPECT_TRUE(same6(m.report->volume, part.volume)) << m.report->volume << " vs " << part.volume;
  EXPECT_LE(std::abs(static_cast<double>(m.filled) - static_cast<double>(mm.filled)), 1e-4 * static_cast<double>(mm.filled));
  EXPECT_TRUE(m.warnings.empty()) << api::to_json(m.warnings).dump();

  // Without the unit the part is 0.03 mm across: said, with the unit that
  // would make sense of it; and a 0.1 mm voxel is larger than all of it.
  const VoxelJobResult unitless = run(metres, mm_params);
  ASSERT_TRUE(has_warning(unitless, "implausible-size")) << api::to_json(unitless.warnings).dump();
  for (const api::JobWarning& w : unitless.warnings) {
    if (w.code != "implausible-size") continue;
    EXPECT_EQ(w.details.at("likely_units"), "m");
    EXPECT_NE(w.message.find("set \"units\": \"m\""), std::string::npos) << w.message;
  }
  EXPECT_TRUE(has_warning(unitless, "voxel-larger-than-part"));
}

TEST(Units, WallLimitsLargerThanThePartAreWarned) {
  Mesh tiny = test::make_box({0, 0, 0}, {0.05, 0.04, 0.02});
  const VoxelJobResult r =
      run(tiny, {{"grid", {{"resolution", 16}}}, {"analyses", {{{"kind", "analysis"}, {"min_wall", 0.8}}}}});
  EXPECT_TRUE(has_warning(r, "wall-limit-exceeds-part")) << api::to_json(r.warnings).dump();
  EXPECT_TRUE(has_warning(r, "implausible-size"));
}

TEST(EmptyResult, AFlatMeshIsWarnedWithWhatToTry) {
  Mesh sheet;
  sheet.vertices = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}};
  sheet.triangles = {{0, 1, 2}};
  for (bool with_report : {true, false}) {
    const VoxelJobResult r = run(sheet, {{"grid", {{"resolution", 16}}}}, with_report);
    EXPECT_EQ(r.filled, 0u);
    ASSERT_TRUE(has_warning(r, "empty-result")) << api::to_json(r.warnings).dump();
    for (const api::JobWarning& w : r.warnings)
      if (w.code == "empty-result") {
        EXPECT_NE(w.message.find("\"mode\": \"surface\""), std::string::npos) << w.message;
        EXPECT_DOUBLE_EQ(w.details.at("surface_area").get<double>(), 50.0);
      }
  }
  // The surface of the same sheet is not empty, and not warned.
  const VoxelJobResult surface = run(sheet, {{"grid", {{"resolution", 16}}}, {"mode", "surface"}});
  EXPECT_GT(surface.filled, 0u);
  EXPECT_FALSE(has_warning(surface, "empty-result"));
}

TEST(InsideAuto, AJobThatMustStreamFallsBackToParityWithAWarning) {
  const Mesh open = test::punched(test::part_named("hex_nut.stl").mesh, 41);
  JobLimits limits;
  limits.stream_above_bytes = 1;  // a stored job: it may stream
  json params = kDefaults;
  params["streaming"] = "on";
  PreparedVoxelJob job = prepare_voxel_job(test::to_binary_stl(open), "nut.stl", api::parse_job_params(params), limits);
  EXPECT_TRUE(job.streamed);
  EXPECT_EQ(job.inside.test, InsideTest::parity);
  EXPECT_EQ(job.params.inside, InsideTest::parity);
  EXPECT_NE(job.inside.reason.find("slab by slab"), std::string::npos) << job.inside.reason;
  ASSERT_FALSE(job.warnings.empty());
  EXPECT_EQ(job.warnings.back().code, "winding-fallback");
}

TEST(InsideAuto, ModesThatCountCrossingsStayParityAndAreWarnedOnOpenMeshes) {
  const Mesh open = test::punched(test::part_named("hex_nut.stl").mesh, 41);
  const VoxelJobResult r = run(open, {{"grid", {{"resolution", 32}}}, {"mode", "coverage"}});
  EXPECT_EQ(r.inside.test, InsideTest::parity);
  EXPECT_FALSE(r.inside.automatic);
  EXPECT_TRUE(has_warning(r, "open-mesh-parity")) << api::to_json(r.warnings).dump();
}

}  // namespace
}  // namespace voxd
