// Meshes of a job's result through the real `voxd serve`
// (GET /v1/jobs/{id}/volume?format=stl|ply|glb): a solid's voxel surface
// and an sdf's zero level set, read back here from the PLY (indexed) and
// the STL (the same triangles): closed, every directed edge once and its
// reverse once, enclosing the job's filled voxels' volume exactly (solid)
// or the uploaded sphere's exact volume within 1 % (sdf). Modes with no
// surface are refused before any work.
#include <cmath>
#include <cstring>
#include <chrono>
#include <map>
#include <sstream>
#include <thread>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "support/http_fixture.h"
#include "support/raw_socket.h"
#include "support/test_meshes.h"

namespace voxd::test {
namespace {

using nlohmann::json;
using SurfaceMeshTest = HttpServiceTest;

struct ReadMesh {
  std::vector<glm::dvec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// A binary little-endian PLY of float x y z and int triangles, read here.
ReadMesh read_ply(const std::string& bytes) {
  ReadMesh m;
  const std::size_t end = bytes.find("end_header\n");
  EXPECT_NE(end, std::string::npos);
  std::istringstream header(bytes.substr(0, end));
  std::string line;
  std::size_t vertices = 0, faces = 0;
  while (std::getline(header, line)) {
    std::sscanf(line.c_str(), "element vertex %zu", &vertices);
    std::sscanf(line.c_str(), "element face %zu", &faces);
  }
  const char* p = bytes.data() + end + 11;
  EXPECT_EQ(bytes.size(), end + 11 + 12 * vertices + 13 * faces);
  for (std::size_t v = 0; v < vertices; ++v, p += 12) {
    float f[3];
    std::memcpy(f, p, 12);
    m.vertices.emplace_back(f[0], f[1], f[2]);
  }
  for (std::size_t t = 0; t < faces; ++t, p += 13) {
    EXPECT_EQ(p[0], 3);
    std::int32_t c[3];
    std::memcpy(c, p + 1, 12);
    m.triangles.push_back({static_cast<std::uint32_t>(c[0]), static_cast<std::uint32_t>(c[1]), static_cast<std::uint32_t>(c[2])});
  }
  return m;
}

// "" when every directed edge is used once and its reverse once.
std::string first_open_edge(const ReadMesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const auto& t : m.triangles)
    for (int e = 0; e < 3; ++e) ++uses[{t[e], t[(e + 1) % 3]}];
  for (const auto& [e, n] : uses) {
    const auto back = uses.find({e.second, e.first});
    if (n != 1 || back == uses.end() || back->second != 1) return std::to_string(e.first) + "->" + std::to_string(e.second);
  }
  return "";
}

double enclosed(const ReadMesh& m) {
  double six = 0;
  for (const auto& t : m.triangles) six += glm::dot(m.vertices[t[0]], glm::cross(m.vertices[t[1]], m.vertices[t[2]]));
  return six / 6;
}

// The STL's triangles are the PLY's, corner for corner.
void expect_same_triangles(const std::string& stl, const ReadMesh& ply) {
  std::uint32_t count = 0;
  ASSERT_GE(stl.size(), 84u);
  std::memcpy(&count, stl.data() + 80, 4);
  ASSERT_EQ(count, ply.triangles.size());
  ASSERT_EQ(stl.size(), 84u + 50u * count);
  for (std::uint32_t t = 0; t < count; ++t) {
    float f[12];
    std::memcpy(f, stl.data() + 84 + 50 * t, 48);
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(glm::dvec3(f[3 + 3 * c], f[4 + 3 * c], f[5 + 3 * c]), ply.vertices[ply.triangles[t][c]]) << t;
  }
}

TEST_F(SurfaceMeshTest, ASolidsVoxelSurfaceIsClosedAndEnclosesItsVoxelsExactly) {
  start();
  // A hollow box with a torus inside its cavity: two parts, a void, curves.
  const Mesh part = concat({make_box({0, 0, 0}, {20, 16, 12}), flipped(make_box({2, 2, 2}, {18, 14, 10})),
                            make_torus({10, 8, 6}, 4, 1.5, 48, 24)});
  const std::string id = finished(submit(to_binary_stl(part), R"({"grid":{"resolution":64},"inside":"parity"})"));
  const json status = expect_json(http().Get(("/v1/jobs/" + id).c_str()), 200, "JobStatus");
  const double h = status.at("grid").at("voxel_size");
  const auto filled = status.at("filled_voxels").get<std::uint64_t>();
  auto res = http().Get(("/v1/jobs/" + id + "/volume?format=ply").c_str());
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_EQ(res->get_header_value("Content-Type"), "application/x-ply");
  EXPECT_NE(res->get_header_value("Content-Disposition").find(id + ".ply"), std::string::npos);
  const ReadMesh ply = read_ply(res->body);
  EXPECT_EQ(first_open_edge(ply), "");
  EXPECT_NEAR(enclosed(ply), static_cast<double>(filled) * h * h * h, 1e-6 * static_cast<double>(filled) * h * h * h);
  // Every vertex on the voxel lattice, in model units.
  const glm::dvec3 origin(status.at("grid").at("origin")[0], status.at("grid").at("origin")[1],
                          status.at("grid").at("origin")[2]);
  for (const glm::dvec3& v : ply.vertices) {
    const glm::dvec3 at = (v - origin) / h;
    ASSERT_NEAR(glm::length(at - glm::round(at)), 0.0, 1e-3);
  }
  expect_same_triangles(volume(id, "?format=stl"), ply);
  const std::string glb = volume(id, "?format=glb");
  ASSERT_GE(glb.size(), 12u);
  EXPECT_EQ(glb.substr(0, 4), "glTF");
}

TEST_F(SurfaceMeshTest, AnSdfsZeroLevelSetIsClosedAndEnclosesTheSphereWithinOnePercent) {
  start();
  const Mesh sphere = make_icosphere({5, -3, 2}, 8, 4);
  const double exact = mesh_volume(sphere);
  for (const char* options : {R"({})", R"({"sign_convention":"inside_positive","units":"voxels"})"}) {
    const std::string id = finished(
        submit(to_binary_stl(sphere), std::string(R"({"grid":{"resolution":48},"mode":"sdf","sdf":)") + options + "}"));
    const ReadMesh ply = read_ply(volume(id, "?format=ply"));
    SCOPED_TRACE(options);
    EXPECT_EQ(first_open_edge(ply), "");
    EXPECT_NEAR(enclosed(ply), exact, 0.01 * exact);
    expect_same_triangles(volume(id, "?format=stl"), ply);
  }
}

TEST_F(SurfaceMeshTest, ResultsWithNoSurfaceAreRefusedBeforeAnyWork) {
  start();
  const auto box = to_binary_stl(make_box({0, 0, 0}, {4, 4, 4}));
  const std::string coverage = finished(submit(box, R"({"grid":{"resolution":8},"mode":"coverage"})"));
  const json p = expect_problem(http().Get(("/v1/jobs/" + coverage + "/volume?format=ply").c_str()), 400, "invalid-query");
  EXPECT_EQ(p.at("detail"),
            "ply is a mesh of the result: the voxel surface of a solid, surface or solid+surface job, or the zero level "
            "set of an sdf job; a coverage job holds u8 values, which have no surface to mesh: ask for rle, raw or nrrd");
  const std::string palette = finished(submit(box, R"({"grid":{"resolution":8},"mode":"palette"})"));
  expect_problem(http().Get(("/v1/jobs/" + palette + "/volume?format=ply").c_str()), 400, "invalid-query");
  // The palette's stl is still its reconstruction.
  EXPECT_EQ(http().Get(("/v1/jobs/" + palette + "/volume?format=stl").c_str())->status, 200);
}

TEST_F(SurfaceMeshTest, AMeshOverThePerJobMemoryIsRefused) {
  // The job's volume (110 KB) fits 2 MB; its surface's ~45 thousand faces do not.
  start({"--max-job-memory", "2000000"});
  const auto ball = to_binary_stl(make_icosphere({0, 0, 0}, 10, 3));
  const std::string id = finished(submit(ball, R"({"grid":{"resolution":96}})"));
  const json p = expect_problem(http().Get(("/v1/jobs/" + id + "/volume?format=glb").c_str()), 422, "limit-exceeded");
  EXPECT_NE(p.at("detail").get<std::string>().find("over the per-job memory of 1 MiB"), std::string::npos) << p;
}

TEST_F(SurfaceMeshTest, AMeshIsHeldFromTheMemoryBudgetUntilItIsSent) {
  using namespace std::chrono_literals;
  // A ball at 384 voxels: a voxel surface of about 700 thousand faces, some
  // 85 MiB to make and a glb (~25 MB) more than loopback's socket buffers
  // hold. Under a budget of 128 MiB one such mesh fits, two at once do not.
  start({"--memory-budget", std::to_string(128u << 20)});
  const std::string id = finished(submit(to_binary_stl(make_icosphere({0, 0, 0}, 10, 4)), R"({"grid":{"resolution":384}})"));
  const std::string get = "/v1/jobs/" + id + "/volume?format=";
  RawSocket slow(server_->port());
  ASSERT_TRUE(slow.send("GET " + get + "glb HTTP/1.1\r\nHost: t\r\n\r\n"));
  // Making the mesh takes a second here, a minute or more under ASan at -O0.
  ASSERT_EQ(slow.read_some(300s).rfind("HTTP/1.1 200", 0), 0u);
  // Its reader stalls: the mesh being sent still holds its memory.
  const auto busy = http().Get((get + "ply").c_str());
  const json p = expect_problem(busy, 429, "memory-busy");
  EXPECT_TRUE(busy->has_header("Retry-After"));
  EXPECT_NE(p.at("detail").get<std::string>().find("the voxel surface needs about"), std::string::npos) << p;
  // Once that reader goes, its mesh and its memory go with it.
  slow.close();
  int status = 0;
  for (int i = 0; i < 300 && status != 200; ++i) {
    if (i) std::this_thread::sleep_for(100ms);
    status = http().Get((get + "ply").c_str())->status;
  }
  EXPECT_EQ(status, 200);
}

}  // namespace
}  // namespace voxd::test
