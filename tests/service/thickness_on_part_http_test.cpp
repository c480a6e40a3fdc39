// The thickness on the part (GET /v1/jobs/{id}/thickness?format=ply|glb|
// json) from a real `voxd serve`: the mesh as uploaded (welded, in the
// user's frame even when the job turned it), each vertex within a voxel of
// the tube's wall, the thin-region ids per vertex, the answer of an
// identical submission, what is refused (and a job kept without its mesh),
// and `voxd analyze` writing the same bytes.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>
#include <tuple>

#include <gtest/gtest.h>

#include "support/http_fixture.h"
#include "support/test_parts.h"
#include "voxd/mesh_report.h"

namespace voxd::test {
namespace {

using nlohmann::json;
using ThicknessOnPart = HttpServiceTest;

// A tube R 3 / r 2.25 (wall 0.75), 2 high, with rings of vertices every
// 0.25 along its faces.
Mesh ringed_tube() {
  std::vector<glm::dvec2> p = {{2.25, 0}};
  for (double z = 0; z < 2 - 1e-9; z += 0.25) p.push_back({3, z});
  for (double z = 2; z > 1e-9; z -= 0.25) p.push_back({2.25, z});
  return make_lathe(p, 96);
}

struct Ply {
  std::vector<glm::vec3> positions;
  std::vector<float> thickness;
  std::size_t faces = 0;
};

Ply parse_ply(const std::string& bytes) {
  Ply ply;
  const std::size_t body = bytes.find("end_header\n") + 11;
  EXPECT_EQ(bytes.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  const std::size_t v = bytes.find("element vertex "), f = bytes.find("element face ");
  const std::size_t nv = std::stoul(bytes.substr(v + 15)), nf = std::stoul(bytes.substr(f + 13));
  EXPECT_EQ(bytes.size(), body + 19 * nv + 13 * nf);
  for (std::size_t i = 0; i < nv && body + 19 * (i + 1) <= bytes.size(); ++i) {
    float x[4];
    std::memcpy(x, bytes.data() + body + 19 * i, 16);
    ply.positions.emplace_back(x[0], x[1], x[2]);
    ply.thickness.push_back(x[3]);
  }
  ply.faces = nf;
  return ply;
}

TEST_F(ThicknessOnPart, EachVertexOfTheUploadedMeshTakesItsWallAndItsThinRegion) {
  start();
  const Mesh tube = ringed_tube();
  const std::vector<std::uint8_t> stl = to_binary_stl(tube);  // a triangle soup: the service welds it
  // Turned before voxelizing: the files stay in the frame of the upload.
  const std::string params =
      R"({"grid":{"voxel_size":0.025,"padding":1},"rotation":{"axis":[1,0.5,0],"angle_deg":30}})";
  const std::string id = finished(submit(stl, params));
  auto get = [&](const std::string& query) {
    auto res = http().Get(("/v1/jobs/" + id + "/thickness?" + query).c_str());
    EXPECT_TRUE(res);
    EXPECT_EQ(res->status, 200) << res->body;
    return res;
  };
  const auto ply_res = get("format=ply&min_wall=0.8");
  EXPECT_EQ(ply_res->get_header_value("Content-Type"), "application/x-ply");
  const Ply ply = parse_ply(ply_res->body);
  // As STL carries it, three corners a triangle, welded in that order.
  Mesh soup;
  for (std::size_t t = 0; t < tube.triangle_count(); ++t) {
    const auto n = static_cast<std::uint32_t>(soup.vertices.size());
    for (int c = 0; c < 3; ++c) soup.vertices.push_back(tube.corner(t, c));
    soup.triangles.push_back({n, n + 1, n + 2});
  }
  const Mesh welded = weld_vertices(soup);
  ASSERT_EQ(ply.positions.size(), welded.vertices.size());
  EXPECT_EQ(ply.faces, welded.triangles.size());
  for (std::size_t i = 0; i < ply.positions.size(); ++i) EXPECT_EQ(ply.positions[i], welded.vertices[i]) << i;
  // Off the rims (2 voxels or more), every vertex is on the wall's faces: 0.75.
  std::size_t compared = 0;
  for (std::size_t i = 0; i < ply.positions.size(); ++i) {
    const float z = ply.positions[i].z;
    if (z < 0.05f || z > 1.95f) continue;
    ++compared;
    EXPECT_NEAR(ply.thickness[i], 0.75, 0.025) << "vertex " << i << " at z " << z;
  }
  EXPECT_EQ(compared, 96u * 14);

  // The JSON: the same values, the surface's statistics, every vertex in
  // the one thin region under min_wall 0.8 and in none under 0.7.
  const json thin = expect_json(get("format=json&min_wall=0.8"), 200, "ThicknessOnPart");
  EXPECT_EQ(thin.at("vertices"), welded.vertices.size());
  EXPECT_EQ(thin.at("unresolved"), 0);
  ASSERT_EQ(thin.at("thickness").size(), ply.thickness.size());
  for (std::size_t i = 0; i < ply.thickness.size(); ++i)
    EXPECT_EQ(static_cast<float>(thin.at("thickness")[i].get<double>()), ply.thickness[i]);
  EXPECT_NEAR(thin.at("mean").get<double>(), 0.75, 0.025);
  ASSERT_EQ(thin.at("thin_regions").size(), 1u);
  EXPECT_EQ(thin.at("thin_regions")[0].at("vertices"), welded.vertices.size());
  for (const auto& r : thin.at("thin_region")) EXPECT_EQ(r, 1);
  const json sound = json::parse(get("format=json&min_wall=0.7")->body);
  EXPECT_TRUE(sound.at("thin_regions").empty());
  for (const auto& r : sound.at("thin_region")) EXPECT_EQ(r, 0);

  // The glb: a binary glTF whose _THICKNESS holds the same values.
  const auto glb = get("format=glb&min_wall=0.8");
  EXPECT_EQ(glb->get_header_value("Content-Type"), "model/gltf-binary");
  EXPECT_EQ(glb->body.substr(0, 4), "glTF");

  // An identical submission is answered from this job's result, mesh and all.
  const std::string again = finished(submit(stl, params));
  ASSERT_NE(again, id);
  auto res = http().Get(("/v1/jobs/" + again + "/thickness?format=ply&min_wall=0.8").c_str());
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200) << res->body;
  EXPECT_EQ(res->body, ply_res->body);

  // `voxd analyze` writes the same files for the same job and thresholds.
  write_file(dir_ + "/tube.stl", stl);
  std::ofstream(dir_ + "/params.json") << params;
  const auto cli = run_process(std::string(VOXD_BINARY) + " analyze " + dir_ + "/tube.stl -o " + dir_ +
                               "/out --params @" + dir_ + "/params.json --min-wall 0.8");
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  EXPECT_EQ(text_of(read_file(dir_ + "/out/thickness-on-part.ply")), ply_res->body);
  EXPECT_EQ(text_of(read_file(dir_ + "/out/thickness-on-part.glb")), glb->body);
  EXPECT_EQ(json::parse(text_of(read_file(dir_ + "/out/thickness-on-part.json"))), thin);
}

TEST_F(ThicknessOnPart, ThresholdsOnAVolumeOrOutOfOrderAreRefusedWithTheField) {
  start();
  const std::string id = finished(submit(to_binary_stl(make_box({0, 0, 0}, {4, 4, 1})), R"({"grid":{"resolution":32}})"));
  json p = expect_problem(http().Get(("/v1/jobs/" + id + "/thickness?format=nrrd&min_wall=0.5").c_str()), 400, "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("min_wall"), std::string::npos) << p.dump();
  EXPECT_NE(p.at("detail").get<std::string>().find("format=ply, glb or json"), std::string::npos) << p.dump();
  p = expect_problem(http().Get(("/v1/jobs/" + id + "/thickness?format=glb&min_wall=2&max_wall=1").c_str()), 400,
                     "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("max_wall must be more than min_wall"), std::string::npos) << p.dump();
  p = expect_problem(http().Get(("/v1/jobs/" + id + "/thickness?format=obj").c_str()), 400, "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("ply"), std::string::npos) << p.dump();

  // A job kept without its mesh (made before the service kept them) says
  // so, and still serves its volume.
  std::filesystem::remove(dir_ + "/data/jobs/" + id + "/artifacts/surface-mesh");
  p = expect_problem(http().Get(("/v1/jobs/" + id + "/thickness?format=ply").c_str()), 400, "invalid-query");
  EXPECT_NE(p.at("detail").get<std::string>().find("kept no mesh"), std::string::npos) << p.dump();
  EXPECT_NE(p.at("detail").get<std::string>().find("submit it again"), std::string::npos) << p.dump();
  auto nrrd = http().Get(("/v1/jobs/" + id + "/thickness?format=nrrd").c_str());
  ASSERT_TRUE(nrrd);
  EXPECT_EQ(nrrd->status, 200);
}

}  // namespace
}  // namespace voxd::test
