// The job parameters contract: what parse_job_params accepts, and the JSON
// path and message of everything it refuses.
#include <fstream>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/job_params.h"
#include "api/modes/coverage_mode.h"
#include "api/modes/sdf_mode.h"
#include "api/param_error.h"

namespace voxd::api {
namespace {

using nlohmann::json;

std::vector<FieldError> errors_of(const json& j) {
  try {
    parse_job_params(j);
  } catch (const InvalidParams& e) {
    return e.errors();
  }
  return {};
}

bool has_error(const std::vector<FieldError>& errors, const std::string& path, const std::string& fragment) {
  for (const auto& e : errors)
    if (e.path == path && e.message.find(fragment) != std::string::npos) return true;
  return false;
}

TEST(JobParams, DefaultsAreSolidParityAt128) {
  const JobParams p = parse_job_params(json::object());
  EXPECT_EQ(p.grid.kind, GridRequest::Kind::resolution);
  EXPECT_EQ(p.grid.resolution, 128);
  EXPECT_EQ(p.mode->voxel_mode(), VoxelMode::solid);
  EXPECT_EQ(p.inside, InsideTest::parity);
  EXPECT_FALSE(p.rotation.has_value());
  EXPECT_FALSE(p.orient_auto);
}

TEST(JobParams, ParsesTheThreeGridForms) {
  JobParams p = parse_job_params(json::parse(R"({"grid": {"resolution": 256, "padding": 1}})"));
  EXPECT_EQ(p.grid.kind, GridRequest::Kind::resolution);
  EXPECT_EQ(p.grid.resolution, 256);
  EXPECT_EQ(p.grid.padding, 1);
  p = parse_job_params(json::parse(R"({"grid": {"voxel_size": 0.25, "padding": 2}})"));
  EXPECT_EQ(p.grid.kind, GridRequest::Kind::voxel_size);
  EXPECT_DOUBLE_EQ(p.grid.voxel_size, 0.25);
  EXPECT_EQ(p.grid.padding, 2);
  p = parse_job_params(json::parse(R"({"grid": {"voxel_size": 0.1, "origin": [-1, 2, 3.5], "dims": [10, 20, 30]}})"));
  EXPECT_EQ(p.grid.kind, GridRequest::Kind::explicit_grid);
  EXPECT_EQ(p.grid.origin, glm::dvec3(-1, 2, 3.5));
  EXPECT_EQ(p.grid.dims, glm::i64vec3(10, 20, 30));
}

TEST(JobParams, ParsesModesInsideTestsAndRotations) {
  JobParams p = parse_job_params(json::parse(
      R"({"mode": "solid+surface", "inside": "winding", "orient": "auto", "rotation": {"axis": [0, 0, 2], "angle_deg": 90}})"));
  EXPECT_EQ(p.mode->voxel_mode(), VoxelMode::solid_and_surface);
  EXPECT_EQ(p.inside, InsideTest::winding);
  EXPECT_TRUE(p.orient_auto);
  ASSERT_TRUE(p.rotation.has_value());
  const glm::dvec3 x = *p.rotation * glm::dvec3(1, 0, 0);
  EXPECT_NEAR(x.x, 0.0, 1e-12);
  EXPECT_NEAR(x.y, 1.0, 1e-12);
  p = parse_job_params(json::parse(R"({"rotation": {"quaternion": [2, 0, 0, 0]}})"));
  ASSERT_TRUE(p.rotation.has_value());
  EXPECT_NEAR(glm::length((*p.rotation)[0] - glm::dvec3(1, 0, 0)), 0.0, 1e-12);
}

TEST(JobParams, ReportsEveryOffendingFieldWithItsPath) {
  const auto errors = errors_of(json::parse(
      R"({"grid": {"resolution": 0, "padding": -1}, "mode": "solidd", "inside": 3, "colour": "red"})"));
  EXPECT_TRUE(has_error(errors, "/grid/resolution", "between 1 and 65536")) << errors.size();
  EXPECT_TRUE(has_error(errors, "/grid/padding", "between 0 and 4096"));
  EXPECT_TRUE(has_error(errors, "/mode", "\"solid\", \"surface\", \"solid+surface\""));
  EXPECT_TRUE(has_error(errors, "/inside", "got number"));
  EXPECT_TRUE(has_error(errors, "/colour", "unknown field"));
  EXPECT_EQ(errors.size(), 5u);
}

TEST(JobParams, DeviceIsAChoiceThatOnlyAModeWithAGpuPathTakesAsCuda) {
  EXPECT_FALSE(parse_job_params(json::object()).device.has_value());  // the machine's default
  for (const char* d : {"auto", "cpu", "cuda"}) {
    const JobParams p = parse_job_params(json{{"mode", "slice"}, {"slice", {{"function", "rock"}}}, {"device", d}});
    EXPECT_EQ(p.device, compute_device_from_string(d)) << d;
  }
  // Whether this machine has a GPU is not the parser's to say: a client
  // validates a cuda job without one.
  EXPECT_TRUE(parse_job_params(json{{"mode", "slice"}, {"slice", {{"function", "rock"}}}, {"device", "cuda"}})
                  .device == ComputeDevice::cuda);
  EXPECT_EQ(parse_job_params(json{{"device", "cpu"}}).device, ComputeDevice::cpu);
  EXPECT_EQ(parse_job_params(json{{"mode", "coverage"}, {"device", "cuda"}}).device, ComputeDevice::cuda);
  EXPECT_EQ(parse_job_params(json{{"mode", "sdf"}, {"device", "cuda"}}).device, ComputeDevice::cuda);
  EXPECT_TRUE(has_error(errors_of(json{{"mode", "palette"}, {"device", "cuda"}}), "/device",
                        "mode \"palette\" runs only on the CPU; drop \"device\" or use auto or cpu"));
  EXPECT_TRUE(has_error(errors_of(json{{"device", "cuda"}}), "/device", "mode \"solid\" runs only on the CPU"));
  EXPECT_TRUE(has_error(errors_of(json{{"device", "gpu"}}), "/device", R"(must be one of "auto", "cpu", "cuda")"));
  EXPECT_TRUE(has_error(errors_of(json{{"device", 1}}), "/device", "got number"));
}

TEST(JobParams, RejectsWrongTypesAndRanges) {
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": {"resolution": 12.5}})")), "/grid/resolution", "integer"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": {"resolution": "256"}})")), "/grid/resolution", "integer"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": {"resolution": 18446744073709551615}})")), "/grid/resolution", "between"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": {"voxel_size": 0}})")), "/grid/voxel_size", "> 0"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": {"voxel_size": -2}})")), "/grid/voxel_size", "> 0"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": 5})")), "/grid", "object"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"([1, 2])")), "", "object"));
}

TEST(JobParams, RejectsInconsistentGridForms) {
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": {"resolution": 64, "voxel_size": 1}})")), "/grid", "either"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": {"voxel_size": 1, "origin": [0, 0, 0]}})")), "/grid", "together"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": {"origin": [0, 0, 0], "dims": [1, 1, 1]}})")), "/grid/voxel_size", "required"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": {"voxel_size": 1, "origin": [0, 0], "dims": [1, 1, 1]}})")), "/grid/origin", "3 numbers"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": {"voxel_size": 1, "origin": [0, 0, 0], "dims": [1, 0, 1]}})")), "/grid/dims/1", "between 1"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"grid": {"voxel_size": 1, "origin": [0, 0, 0], "dims": [1, 1, 1], "padding": 1}})")), "/grid/padding", "unknown field"));
}

TEST(JobParams, RejectsBadRotations) {
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"rotation": {"axis": [0, 0, 0], "angle_deg": 10}})")), "/rotation/axis", "zero"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"rotation": {"axis": [0, 0, 1]}})")), "/rotation/angle_deg", "required"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"rotation": {"quaternion": [0, 0, 0, 0]}})")), "/rotation/quaternion", "zeros"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"rotation": {"quaternion": [1, 0, 0]}})")), "/rotation/quaternion", "4 numbers"));
  EXPECT_TRUE(has_error(errors_of(json::parse(R"({"orient": "sideways"})")), "/orient", "\"auto\""));
}

TEST(JobParams, MalformedJsonTextIsAnInvalidParamsError) {
  try {
    parse_job_params_text("{\"grid\": ");
    FAIL();
  } catch (const InvalidParams& e) {
    ASSERT_EQ(e.errors().size(), 1u);
    EXPECT_NE(e.errors()[0].message.find("malformed JSON"), std::string::npos);
  }
}

TEST(JobParams, EveryExampleOfThePublishedSchemaIsAccepted) {
  std::ifstream in(std::string(VOXD_SOURCE_DIR) + "/proto-schemas/job-params.schema.json");
  ASSERT_TRUE(in) << "proto-schemas/job-params.schema.json missing";
  const json schema = json::parse(in);
  ASSERT_GE(schema.at("examples").size(), 3u);
  for (const auto& example : schema.at("examples")) EXPECT_NO_THROW(parse_job_params(example)) << example.dump();
}

TEST(JobParams, CoverageModeDefaultsToExactIntegrationWithFourByFourRaysAsBytes) {
  const JobParams p = parse_job_params(json::parse(R"({"mode": "coverage"})"));
  ASSERT_TRUE(p.options_as<CoverageParams>() != nullptr);
  EXPECT_FALSE(p.options_as<SdfParams>() != nullptr);
  EXPECT_EQ(p.mode_name(), "coverage");
  EXPECT_EQ(p.options_as<CoverageParams>()->options.sampling, CoverageSampling::exact);
  EXPECT_EQ(p.options_as<CoverageParams>()->options.rays, 4);
  EXPECT_FALSE(p.options_as<CoverageParams>()->threshold.has_value());
  EXPECT_FALSE(p.options_as<CoverageParams>()->float_values);
  EXPECT_TRUE(p.has_values());
}

TEST(JobParams, CoverageOptionsAreParsed) {
  JobParams p = parse_job_params(json::parse(R"({"mode": "coverage", "coverage": {"sampling": "stochastic", "rays": 8, "seed": 18446744073709551615, "values": "f32"}})"));
  EXPECT_EQ(p.options_as<CoverageParams>()->options.sampling, CoverageSampling::stochastic);
  EXPECT_EQ(p.options_as<CoverageParams>()->options.rays, 8);
  EXPECT_EQ(p.options_as<CoverageParams>()->options.seed, UINT64_MAX);
  EXPECT_TRUE(p.options_as<CoverageParams>()->float_values);
  p = parse_job_params(json::parse(R"({"mode": "coverage", "coverage": {"sampling": "uniform", "rays": 2, "points": 16}})"));
  EXPECT_EQ(p.options_as<CoverageParams>()->options.sampling, CoverageSampling::uniform);
  EXPECT_EQ(p.options_as<CoverageParams>()->options.points, 16);
  // A threshold turns the result into bits.
  p = parse_job_params(json::parse(R"({"mode": "coverage", "coverage": {"threshold": 0.25}})"));
  EXPECT_FLOAT_EQ(*p.options_as<CoverageParams>()->threshold, 0.25f);
  EXPECT_FALSE(p.has_values());
}

TEST(JobParams, CoverageOptionsThatWouldBeIgnoredAreRefusedAtTheirPaths) {
  auto e = errors_of(json::parse(R"({"mode": "coverage", "coverage": {"points": 4, "seed": 3}})"));
  EXPECT_TRUE(has_error(e, "/coverage/points", "only to sampling \"uniform\"")) << e.size();
  EXPECT_TRUE(has_error(e, "/coverage/seed", "only to sampling \"stochastic\""));
  e = errors_of(json::parse(R"({"mode": "coverage", "coverage": {"threshold": 0.5, "values": "f32", "rays": 65, "sampling": "random"}, "inside": "winding"})"));
  EXPECT_TRUE(has_error(e, "/coverage/values", "drop one of the two"));
  EXPECT_TRUE(has_error(e, "/coverage/rays", "between 1 and 64"));
  EXPECT_TRUE(has_error(e, "/coverage/sampling", "\"exact\", \"uniform\", \"stochastic\""));
  EXPECT_TRUE(has_error(e, "/inside", "does not apply"));
  e = errors_of(json::parse(R"({"mode": "coverage", "coverage": {"threshold": 0, "seed": -1, "colour": 1}})"));
  EXPECT_TRUE(has_error(e, "/coverage/threshold", "> 0"));
  EXPECT_TRUE(has_error(e, "/coverage/seed", "non-negative integer"));
  EXPECT_TRUE(has_error(e, "/coverage/colour", "unknown field"));
}

TEST(JobParams, SdfModeDefaultsToABandOfThreeVoxelsInsideNegativeInModelUnits) {
  const JobParams p = parse_job_params(json::parse(R"({"mode": "sdf", "inside": "winding"})"));
  ASSERT_TRUE(p.options_as<SdfParams>() != nullptr);
  EXPECT_EQ(p.mode_name(), "sdf");
  EXPECT_DOUBLE_EQ(p.options_as<SdfParams>()->band, 3.0);
  EXPECT_FALSE(p.options_as<SdfParams>()->full);
  EXPECT_EQ(p.options_as<SdfParams>()->sign, SignConvention::inside_negative);
  EXPECT_TRUE(p.options_as<SdfParams>()->model_units);
  // The sign comes from the job's inside test, asked for here by name.
  EXPECT_EQ(p.inside, InsideTest::winding);
  EXPECT_FALSE(p.inside_auto);
  EXPECT_TRUE(p.has_values());
}

TEST(JobParams, SdfOptionsAreParsedAndCheckedAtTheirPaths) {
  JobParams p = parse_job_params(json::parse(R"({"mode": "sdf", "sdf": {"band": "full", "sign_convention": "inside_positive", "units": "voxels"}})"));
  EXPECT_TRUE(p.options_as<SdfParams>()->full);
  EXPECT_EQ(p.options_as<SdfParams>()->sign, SignConvention::inside_positive);
  EXPECT_FALSE(p.options_as<SdfParams>()->model_units);
  p = parse_job_params(json::parse(R"({"mode": "sdf", "sdf": {"band": 1.5}})"));
  EXPECT_DOUBLE_EQ(p.options_as<SdfParams>()->band, 1.5);
  auto e = errors_of(json::parse(R"({"mode": "sdf", "sdf": {"band": "wide", "units": "mm", "sign_convention": "negative"}})"));
  EXPECT_TRUE(has_error(e, "/sdf/band", "or \"full\""));
  EXPECT_TRUE(has_error(e, "/sdf/units", "\"model\", \"voxels\""));
  EXPECT_TRUE(has_error(e, "/sdf/sign_convention", "\"inside_negative\", \"inside_positive\""));
  e = errors_of(json::parse(R"({"mode": "sdf", "sdf": {"band": 0}})"));
  EXPECT_TRUE(has_error(e, "/sdf/band", "> 0"));
}

TEST(JobParams, OptionsForAnotherModeAreRefused) {
  auto e = errors_of(json::parse(R"({"sdf": {"band": 2}})"));
  EXPECT_TRUE(has_error(e, "/sdf", "but the mode is \"solid\""));
  e = errors_of(json::parse(R"({"mode": "sdf", "coverage": {"rays": 2}})"));
  EXPECT_TRUE(has_error(e, "/coverage", "but the mode is \"sdf\""));
  // A bad mode is reported once, not again for its options.
  e = errors_of(json::parse(R"({"mode": "grey", "coverage": {"rays": 2}})"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].path, "/mode");
}

}  // namespace
}  // namespace voxd::api
