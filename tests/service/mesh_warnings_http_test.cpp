// Warnings, the inside test chosen from the mesh and the mesh file's unit,
// as a client of a real `voxd serve` sees them in the job status (checked
// against the OpenAPI document with every status the fixture reads): an
// open part written inside out, the same part closed, an identical
// resubmission, a part in metres, parity asked for an open part, and a
// unit the service does not know.
#include <cmath>

#include <gtest/gtest.h>

#include "support/http_fixture.h"
#include "support/test_parts.h"

namespace voxd::test {
namespace {

using nlohmann::json;
using MeshWarnings = HttpServiceTest;

json warning_named(const json& status, const std::string& code) {
  for (const json& w : status.at("warnings"))
    if (w.at("code") == code) return w;
  return nullptr;
}

TEST_F(MeshWarnings, AnOpenPartWrittenInsideOutIsTurnedRoundFilledAndSaidSo) {
  start();
  const Mesh nut = part_named("hex_nut.stl").mesh;
  const std::string params = R"({"grid":{"resolution":80,"padding":2}})";
  auto status_of = [&](const std::string& id) { return expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus"); };

  const json closed = status_of(finished(submit(to_binary_stl(nut), params)));
  EXPECT_EQ(closed.at("inside"), json({{"test", "parity"},
                                       {"chosen", "auto"},
                                       {"reason", "the mesh is closed: parity, exact and fastest"}}));
  EXPECT_EQ(closed.at("warnings"), json::array());
  EXPECT_EQ(closed.at("units"), json({{"mesh", "mm"}, {"lengths", "mm"}}));

  // Closed and inside out: turned round, and its report (volume, edges) is
  // of the mesh as turned, the same as the part written outward.
  const json turned = status_of(finished(submit(to_binary_stl(flipped(nut)), params)));
  EXPECT_EQ(turned.at("mesh").at("orientation").at("inverted_components"), 1);
  EXPECT_EQ(turned.at("mesh").at("volume"), closed.at("mesh").at("volume"));
  EXPECT_GT(turned.at("mesh").at("volume").get<double>(), 0.0);
  EXPECT_EQ(turned.at("filled_voxels"), closed.at("filled_voxels"));

  const std::vector<std::uint8_t> inverted = to_binary_stl(flipped(punched(nut, 41)));
  const json accepted = submit(inverted, params);
  // The choice and the preparing's warnings are there from the start.
  EXPECT_EQ(accepted.at("inside").at("test"), "winding");
  EXPECT_FALSE(warning_named(accepted, "mesh-inverted").is_null()) << accepted.dump();
  const json open = status_of(finished(accepted));
  EXPECT_EQ(open.at("inside").at("test"), "winding");
  EXPECT_EQ(open.at("inside").at("chosen"), "auto");
  const json inverted_warning = warning_named(open, "mesh-inverted");
  ASSERT_FALSE(inverted_warning.is_null()) << open.at("warnings").dump();
  EXPECT_EQ(inverted_warning.at("details").at("inverted_components"), 1);
  EXPECT_EQ(open.at("mesh").at("orientation").at("inverted_components"), 1);
  EXPECT_GT(open.at("mesh").at("boundary_edges").get<int>(), 0);
  const double a = open.at("filled_voxels").get<double>(), b = closed.at("filled_voxels").get<double>();
  EXPECT_LT(std::abs(a - b) / b, 0.01) << a << " inside out and open, " << b << " closed";

  // The analysis report is read with the same warnings and inside test.
  const std::string open_id = open.at("id");
  const json report = expect_json(http().Get(("/v1/jobs/" + open_id + "/analysis?thickness=false&skin=false").c_str()), 200,
                                  "Analysis");
  EXPECT_EQ(report.at("warnings"), open.at("warnings"));
  EXPECT_EQ(report.at("inside"), open.at("inside"));
  EXPECT_EQ(report.at("unit"), "mm");

  // An identical submission is answered from the first, warnings and all.
  const json again = submit(inverted, params);
  EXPECT_TRUE(again.at("cached").get<bool>());
  EXPECT_EQ(again.at("warnings"), open.at("warnings"));
  EXPECT_EQ(again.at("inside"), open.at("inside"));

  // Parity by name on the open part: done as asked, and warned.
  const json parity = status_of(finished(submit(inverted, R"({"grid":{"resolution":80,"padding":2},"inside":"parity"})")));
  EXPECT_EQ(parity.at("inside"), json({{"test", "parity"}, {"chosen", "asked"}}));
  EXPECT_FALSE(warning_named(parity, "open-mesh-parity").is_null()) << parity.at("warnings").dump();
}

TEST_F(MeshWarnings, APartInMetresIsReportedInMillimetres) {
  start();
  const Part bushing = part_named("flanged_bushing.stl");
  Mesh metres = bushing.mesh;
  for (glm::vec3& v : metres.vertices) v = glm::vec3(glm::dvec3(v) / 1000.0);
  const json mm = expect_json(http().Get(("/v1/jobs/" + finished(submit(to_binary_stl(bushing.mesh),
                                                                          R"({"grid":{"voxel_size":0.1}})")))
                                              .c_str()),
                              200, "JobStatus");
  const json m = expect_json(
      http().Get(("/v1/jobs/" + finished(submit(to_binary_stl(metres), R"({"grid":{"voxel_size":0.1},"units":"m"})"))).c_str()),
      200, "JobStatus");
  EXPECT_EQ(m.at("units"), json({{"mesh", "m"}, {"lengths", "mm"}}));
  EXPECT_EQ(m.at("grid").at("dims"), mm.at("grid").at("dims"));
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(m.at("mesh").at("bbox_max").at(i).get<double>(), mm.at("mesh").at("bbox_max").at(i).get<double>(),
                1e-5 * std::abs(mm.at("mesh").at("bbox_max").at(i).get<double>()) + 1e-9);
  EXPECT_NEAR(m.at("mesh").at("volume").get<double>(), bushing.volume, 1e-5 * bushing.volume);
  EXPECT_EQ(m.at("warnings"), json::array());

  // Without "units" it is 0.05 mm across: accepted, and the status says
  // which unit would make sense of it.
  const json unitless = submit(to_binary_stl(metres), R"({"grid":{"resolution":32}})");
  const json w = warning_named(unitless, "implausible-size");
  ASSERT_FALSE(w.is_null()) << unitless.dump();
  EXPECT_EQ(w.at("details").at("likely_units"), "m");
  finished(unitless);

  const json p = expect_problem(post_multipart(http(), "/v1/jobs", to_binary_stl(metres), "part.stl", R"({"units":"metres"})"),
                                422, "invalid-params");
  EXPECT_EQ(p.at("errors").at(0).at("path"), "/units");
}

}  // namespace
}  // namespace voxd::test
