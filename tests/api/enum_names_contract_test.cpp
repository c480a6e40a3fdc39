// Each enum's names are written once, in its table (voxd/enum_names.h); the
// published contract lists them again for clients. This holds the two equal,
// in order, so a name added to one and not the other fails here, not in a
// client's validator.
#include <algorithm>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/analysis_request.h"
#include "api/job_mode.h"
#include "api/job_params.h"
#include "voxd/encode/volume_format.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/voxelize/coverage.h"
#include "voxd/voxelize/palette.h"
#include "voxd/voxelize/sdf.h"
#include "voxd/voxelize/slice_functions.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using nlohmann::json;

json schema(const char* file) {
  std::ifstream in(std::string(VOXD_SOURCE_DIR) + "/proto-schemas/" + file);
  if (!in) throw std::runtime_error(std::string("missing proto-schemas/") + file);
  return json::parse(in);
}

std::vector<std::string> contract_enum(const json& doc, const char* pointer) {
  return doc.at(json::json_pointer(pointer)).at("enum").get<std::vector<std::string>>();
}

template <typename E, std::size_t N>
std::vector<std::string> table(const EnumNames<E, N>& names) {
  std::vector<std::string> out;
  for (const auto& n : names) out.emplace_back(n.name);
  return out;
}

template <typename E, std::size_t N>
void expect_round_trip(const EnumNames<E, N>& names) {
  std::set<std::string> seen;
  for (const auto& n : names) {
    EXPECT_TRUE(seen.insert(n.name).second) << "duplicate name " << n.name;
    EXPECT_EQ(value_named(names, n.name), n.value) << n.name;
    EXPECT_STREQ(name_of(names, n.value), n.name);
  }
  EXPECT_FALSE(value_named(names, "no-such-name"));
}

TEST(EnumNames, EveryTableReadsBackItsOwnNamesAndNoOther) {
  expect_round_trip(kInsideTestNames);
  expect_round_trip(kVoxelModeNames);
  expect_round_trip(kCoverageSamplingNames);
  expect_round_trip(kSignConventionNames);
  expect_round_trip(kPaletteMetricNames);
  expect_round_trip(kSliceFunctionNames);
  expect_round_trip(kVolumeFormatNames);
  expect_round_trip(kMeshFormatNames);
  expect_round_trip(kRadiographyMeasureNames);
  expect_round_trip(kPeelMetricNames);
  expect_round_trip(api::kAnalysisKindNames);
  expect_round_trip(api::kStreamingNames);
}

TEST(EnumNames, TheJobParametersSchemaListsTheEnginesNames) {
  const json s = schema("job-params.schema.json");
  // "auto" chooses one of the engine's tests from the mesh (api/inside_choice.h).
  std::vector<std::string> inside = {"auto"};
  for (const std::string& name : table(kInsideTestNames)) inside.push_back(name);
  EXPECT_EQ(contract_enum(s, "/properties/inside"), inside);
  EXPECT_EQ(contract_enum(s, "/properties/units"), table(api::kLengthUnitNames));
  EXPECT_EQ(contract_enum(s, "/properties/streaming"), table(api::kStreamingNames));
  EXPECT_EQ(contract_enum(s, "/properties/coverage/properties/sampling"), table(kCoverageSamplingNames));
  EXPECT_EQ(contract_enum(s, "/properties/sdf/properties/sign_convention"), table(kSignConventionNames));
  EXPECT_EQ(contract_enum(s, "/properties/palette/properties/metric"), table(kPaletteMetricNames));
  EXPECT_EQ(contract_enum(s, "/properties/slice/properties/function"), table(kSliceFunctionNames));
  EXPECT_EQ(contract_enum(s, "/properties/analyses/items/oneOf/1/properties/measure"), table(kRadiographyMeasureNames));
  EXPECT_EQ(contract_enum(s, "/$defs/peel_metric"), table(kPeelMetricNames));
}

// The modes the schema refuses "device": "cuda" for are exactly those
// whose work runs only on the CPU (JobMode::runs_on_gpu): a client that
// validates against the contract is refused where voxd would refuse it.
TEST(EnumNames, TheJobParametersSchemaRefusesCudaForTheModesThatRunOnlyOnTheCpu) {
  const json s = schema("job-params.schema.json");
  std::vector<std::string> cpu_only;
  for (const json& rule : s.at("allOf")) {
    const json mode = rule.value("if", json::object()).value("properties", json::object()).value("mode", json::object());
    if (mode.contains("enum") && rule.at("then").dump().find("cuda") != std::string::npos)
      cpu_only = mode.at("enum").get<std::vector<std::string>>();
  }
  std::vector<std::string> expected;
  for (const api::JobMode* mode : api::job_modes())
    if (!mode->runs_on_gpu()) expected.emplace_back(mode->name());
  std::sort(cpu_only.begin(), cpu_only.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(cpu_only, expected);
  EXPECT_FALSE(expected.empty());
}

TEST(EnumNames, TheOpenApiDocumentListsTheServicesNames) {
  const json o = schema("openapi.json");
  EXPECT_EQ(contract_enum(o, "/components/schemas/VolumeFormat"), table(kVolumeFormatNames));
  // "unknown" is the decoder's word for a mesh it could not place, never a
  // job's: a job with such a mesh is refused before it has a status.
  std::vector<std::string> decodable = table(kMeshFormatNames);
  decodable.erase(decodable.begin());
  EXPECT_EQ(contract_enum(o, "/components/schemas/JobStatus/properties/mesh_format"), decodable);
}

}  // namespace
}  // namespace voxd
