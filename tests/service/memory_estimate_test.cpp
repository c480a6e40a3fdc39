// The memory budget's estimates (server/pipeline/job_pipeline.h,
// server/jobs/job_analyses.h) against the measured peak of real `voxd`
// processes doing the same work (ru_maxrss from wait4): an estimate below
// the measurement would let the service admit more than its budget.
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/analysis_request.h"
#include "api/job_params.h"
#include "server/pipeline/job_pipeline.h"
#include "server/jobs/job_analyses.h"
#include "support/ply_writer.h"
#include "support/run_process.h"
#include "support/test_meshes.h"

namespace voxd {
namespace {

// What a process takes before any work (the binary, its libraries, the
// allocator's arenas), measured by `voxd --version`; AddressSanitizer's
// shadow memory and redzones add to it.
#if defined(__SANITIZE_ADDRESS__)
constexpr std::uint64_t kSlack = std::uint64_t{200} << 20;
#else
constexpr std::uint64_t kSlack = std::uint64_t{32} << 20;
#endif

// Peak resident bytes of `voxd ARGS...`, which must exit 0.
std::uint64_t peak_of(const std::vector<std::string>& args) {
  std::vector<std::string> all = {VOXD_BINARY};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    // Freed memory goes back at once, as in the release build.
    ::setenv("ASAN_OPTIONS", "quarantine_size_mb=0:detect_leaks=0", 1);
    std::freopen("/dev/null", "w", stdout);
    std::freopen("/dev/null", "w", stderr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  rusage usage{};
  ::wait4(pid, &status, 0, &usage);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "voxd " << args.at(0) << " failed";
  return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;
}

class MemoryEstimateTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::make_temp_dir("voxd-memory");
    mesh_path_ = dir_ + "/ball.stl";
    mesh_bytes_ = test::to_binary_stl(test::make_icosphere({0, 0, 0}, 1, 5));
    test::write_file(mesh_path_, mesh_bytes_);
    baseline_ = peak_of({"--version"});
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  PreparedVoxelJob prepare(const std::string& params) {
    return prepare_voxel_job(mesh_bytes_, "ball.stl", api::parse_job_params_text(params), JobLimits{});
  }

  std::string dir_, mesh_path_;
  std::vector<std::uint8_t> mesh_bytes_;
  std::uint64_t baseline_ = 0;
};

TEST_F(MemoryEstimateTest, EveryModeStaysUnderItsEstimate) {
  for (const std::string params :
       {R"({"grid": {"resolution": 256}})", R"({"grid": {"resolution": 256}, "inside": "vote"})",
        R"({"grid": {"resolution": 256}, "mode": "solid+surface"})",
        R"({"grid": {"resolution": 192}, "mode": "coverage"})",
        R"({"grid": {"resolution": 192}, "mode": "coverage", "coverage": {"values": "f32"}})",
        R"({"grid": {"resolution": 192}, "mode": "sdf", "sdf": {"band": 3}})",
        R"({"grid": {"resolution": 160}, "mode": "sdf", "sdf": {"band": "full"}})",
        R"({"grid": {"resolution": 192}, "mode": "palette", "palette": {"elements": 46, "rays": 8, "points": 2}})",
        R"({"grid": {"resolution": 192}, "mode": "slice", "slice": {"function": "marble"}})"}) {
    const PreparedVoxelJob job = prepare(params);
    std::ofstream(dir_ + "/params.json") << params;
    const std::uint64_t peak =
        peak_of({"voxelize", mesh_path_, "-o", dir_ + "/out.rle", "--params", "@" + dir_ + "/params.json"});
    const std::uint64_t allowed = baseline_ + kSlack + mesh_bytes_.size() + mesh_memory(job.mesh) + job.memory_estimate;
    EXPECT_LE(peak, allowed) << params << ": measured " << (peak >> 20) << " MiB, estimate "
                             << (job.memory_estimate >> 20) << " MiB";
    // And the estimate is not wildly above what runs (it would refuse work
    // the machine can do).
    EXPECT_LE(job.memory_estimate, 4 * peak) << params;
  }
}

TEST_F(MemoryEstimateTest, AnalysesStayUnderTheirEstimate) {
  const std::string params = R"({"grid": {"resolution": 192}})";
  const PreparedVoxelJob job = prepare(params);
  for (const auto& [kind, fields] : std::vector<std::pair<api::AnalysisKind, api::Fields>>{
           {api::AnalysisKind::thickness, {{"format", "raw"}}},
           {api::AnalysisKind::analysis, {}},
           {api::AnalysisKind::radiography, {{"peel", "3"}, {"peel_metric", "euclidean"}}},
           {api::AnalysisKind::section, {{"axis", "x"}, {"index", "96"}, {"colour", "thickness"}}}}) {
    const api::AnalysisRequest request = api::parse_analysis_request(kind, fields, "");
    nlohmann::json entry = {{"kind", to_string(kind)}};
    for (const auto& [k, v] : fields) entry[k] = v;
    if (kind == api::AnalysisKind::radiography) entry["peel"] = 3;
    if (kind == api::AnalysisKind::section) entry["index"] = 96;
    std::ofstream(dir_ + "/job.json") << nlohmann::json{{"grid", {{"resolution", 192}}}, {"analyses", {entry}}}.dump();
    std::filesystem::remove_all(dir_ + "/out");
    // `voxd analyze` also writes its standard report (radiographs,
    // sections, previews, local thickness), whose peak the analysis with
    // thickness bounds.
    const std::uint64_t peak = peak_of({"analyze", mesh_path_, "-o", dir_ + "/out", "--params", "@" + dir_ + "/job.json"});
    const api::AnalysisRequest report = api::parse_analysis_request(api::AnalysisKind::analysis, {}, "");
    const std::uint64_t estimate = std::max(server::estimate_analysis_memory(request, job.grid),
                                            server::estimate_analysis_memory(report, job.grid));
    const std::uint64_t allowed = baseline_ + kSlack + mesh_bytes_.size() + mesh_memory(job.mesh) + job.memory_estimate + estimate;
    EXPECT_LE(peak, allowed) << request.artifact_key() << ": measured " << (peak >> 20) << " MiB, estimate "
                             << (estimate >> 20) << " MiB";
  }
}

TEST_F(MemoryEstimateTest, DecodingStaysUnderItsEstimate) {
  struct Case {
    std::string name;
    std::uint64_t size, estimate;
  };
  std::vector<Case> cases;
  auto add = [&](const std::string& name, const std::vector<std::uint8_t>& bytes) {
    test::write_file(dir_ + "/" + name, bytes);
    cases.push_back({name, bytes.size(), decode_memory_estimate(bytes, name, {})});
  };
  {
    // Many vertices for few faces, the shape of the 60 MB PLY that held 229 MB.
    Mesh mesh = test::make_box({0, 0, 0}, {1, 1, 1});
    mesh.vertices.resize(3'000'000, glm::vec3(0.5f));
    test::PlyOptions binary;
    binary.encoding = test::PlyOptions::Encoding::binary_little_endian;
    add("many.ply", test::to_ply(mesh, binary));
    add("ball.stl", test::to_binary_stl(test::make_icosphere({0, 0, 0}, 1, 7)));
    const std::string obj = test::to_obj(test::make_icosphere({0, 0, 0}, 1, 6));
    add("ball.obj", std::vector<std::uint8_t>(obj.begin(), obj.end()));
  }
  // A forked child starts with this process's resident size as its peak:
  // the meshes made above are given back first.
  ::malloc_trim(0);
  for (const Case& c : cases) {
    const std::uint64_t peak = peak_of({"inspect", dir_ + "/" + c.name});
    // inspect maps the file and welds the mesh for its report: the weld's
    // tables are the mesh again.
    const std::uint64_t allowed = baseline_ + kSlack + c.size + 2 * c.estimate;
    EXPECT_LE(peak, allowed) << c.name << ": measured " << (peak >> 20) << " MiB, allowed " << (allowed >> 20) << " MiB";
  }
}

}  // namespace
}  // namespace voxd
