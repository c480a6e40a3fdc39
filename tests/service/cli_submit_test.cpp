// `voxd submit` against a real `voxd serve`: the file it writes is the
// bytes `voxd voxelize` writes for the same job, standard output holds only
// the volume, errors exit as voxelize's do with the service's problem type,
// and a terminal gets a progress bar.
#include <atomic>
#include <filesystem>
#include <fstream>
#include <thread>

#include "support/http_fixture.h"
#include "support/run_process.h"
#include "support/test_meshes.h"

namespace voxd::test {
namespace {

using nlohmann::json;

class SubmitCli : public HttpServiceTest {
 protected:
  std::string server_url() const { return "http://127.0.0.1:" + std::to_string(server_->port()); }
  std::string mesh_file(const std::string& name, const std::vector<std::uint8_t>& bytes) {
    write_file(dir_ + "/" + name, bytes);
    return dir_ + "/" + name;
  }
  ProcessResult submit_cli(const std::string& flags, const std::string& env = "") {
    return run_process(env + " " + std::string(VOXD_BINARY) + " submit " + flags);
  }
};

TEST_F(SubmitCli, WritesTheBytesVoxelizeWrites) {
  start();
  const auto mesh = to_binary_stl(make_icosphere({1, 2, 3}, 4.0, 3));
  const std::string path = mesh_file("ball.stl", mesh);
  for (const auto& [params, format] : std::vector<std::pair<std::string, std::string>>{
           {R"({"grid":{"resolution":30,"padding":1}})", "rle"},
           {R"({"grid":{"resolution":30,"padding":1}})", "binvox"},
           {R"({"mode":"sdf","grid":{"resolution":24,"padding":2},"sdf":{"band":2}})", "nrrd"},
           {R"({"mode":"coverage","grid":{"resolution":20}})", "raw"}}) {
    SCOPED_TRACE(params + " " + format);
    std::ofstream(dir_ + "/p.json") << params;
    const std::string out = dir_ + "/submitted." + format;
    const auto r = submit_cli(path + " -o " + out + " --params @" + dir_ + "/p.json --server " + server_url());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(text_of(read_file(out)), cli_volume(mesh, "ball.stl", params, format));
    EXPECT_NE(r.err.find("output:  " + out), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out + ".partial"));
  }
}

TEST_F(SubmitCli, StandardOutputHoldsOnlyTheVolumeAndTheServerComesFromTheEnvironment) {
  start();
  const auto mesh = to_binary_stl(make_box({0, 0, 0}, {2, 3, 4}));
  const std::string path = mesh_file("box.stl", mesh);
  const auto r = submit_cli(path + " -o - --format raw --resolution 16 --json --report", "VOXD_SERVER=" + server_url());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string expected = cli_volume(mesh, "box.stl", R"({"grid":{"resolution":16}})", "raw");
  EXPECT_EQ(r.out, expected);
  const json summary = json::parse(r.err);
  EXPECT_EQ(summary.at("server"), server_url());
  EXPECT_EQ(summary.at("output").at("bytes").get<std::size_t>(), expected.size());
  EXPECT_EQ(summary.at("grid").at("dims"), json::array({8, 12, 16}));
  EXPECT_EQ(summary.at("report").at("watertight"), true);
  EXPECT_EQ(summary.at("filled_voxels"), 8 * 12 * 16);
  // The job is the service's: its status says so.
  auto res = http().Get(("/v1/jobs/" + summary.at("job").get<std::string>()).c_str());
  ASSERT_TRUE(res);
  EXPECT_EQ(json::parse(res->body).at("state"), "succeeded");
}

TEST_F(SubmitCli, TheJobsNameAndTagsAreTheFlagsOrTheFilesName) {
  start();
  const std::string path = mesh_file("box.stl", to_binary_stl(make_box({0, 0, 0}, {2, 3, 4})));
  auto job_of = [&](const ProcessResult& r) {
    EXPECT_EQ(r.exit_code, 0) << r.err;
    auto res = http().Get(("/v1/jobs/" + json::parse(r.out).at("job").get<std::string>()).c_str());
    return json::parse(res->body);
  };
  const json named = job_of(submit_cli(path + " -o " + dir_ + "/a.rle --resolution 8 --json --name 'pump housing' --tags "
                                       "'{\"project\": \"pump\"}' --server " + server_url()));
  EXPECT_EQ(named.at("name"), "pump housing");
  EXPECT_EQ(named.at("tags"), json({{"project", "pump"}}));
  const json plain = job_of(submit_cli(path + " -o " + dir_ + "/b.rle --resolution 9 --json --server " + server_url()));
  EXPECT_EQ(plain.at("name"), "box.stl");
  EXPECT_EQ(plain.at("tags"), json::object());
  // A callback the service does not allow is its 422, with the field.
  const auto refused = submit_cli(path + " -o " + dir_ + "/c.rle --callback http://127.0.0.1:1/ --server " + server_url());
  EXPECT_EQ(refused.exit_code, 2) << refused.err;
  EXPECT_NE(refused.err.find("invalid-params"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("allow-list"), std::string::npos) << refused.err;
}

TEST_F(SubmitCli, AnalysesAskedForAreWrittenBesideTheVolumeAsTheServiceServesThem) {
  start();
  // A hollow box 20 x 16 x 12, walls 2 thick: its void is 16 x 12 x 8.
  const auto mesh = to_binary_stl(concat({make_box({0, 0, 0}, {20, 16, 12}), flipped(make_box({2, 2, 2}, {18, 14, 10}))}));
  const std::string path = mesh_file("hollow.stl", mesh);
  const auto r = submit_cli(path + " -o " + dir_ + "/hollow.rle --resolution 40 --json --server " + server_url() +
                            " --analysis 'analysis?min_wall=1.5' --analysis 'radiography?axis=z&format=png16' --analysis 'section?axis=z&index=20'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json summary = json::parse(r.out);
  ASSERT_EQ(summary.at("analyses").size(), 3u) << summary.dump();
  EXPECT_EQ(summary.at("analyses").at(0).at("path"), dir_ + "/hollow.analysis.json");
  EXPECT_EQ(summary.at("analyses").at(1).at("path"), dir_ + "/hollow.radiography.png");
  EXPECT_EQ(summary.at("analyses").at(2).at("path"), dir_ + "/hollow.section.png");
  // Each file is what the service serves at the analysis's URL.
  for (const json& a : summary.at("analyses")) {
    auto res = http().Get(a.at("url").get<std::string>().c_str());
    ASSERT_TRUE(res);
    EXPECT_EQ(text_of(read_file(a.at("path"))), res->body) << a.dump();
  }
  // The analysis finds the box's one void, of the inner box's volume.
  const json analysis = json::parse(text_of(read_file(dir_ + "/hollow.analysis.json")));
  ASSERT_EQ(analysis.at("voids").at("count"), 1) << analysis.at("voids").dump();
  // A wrong kind is a usage error before anything is sent.
  const auto bad = submit_cli(path + " -o " + dir_ + "/x.rle --analysis thikness --server " + server_url());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("radiography"), std::string::npos) << bad.err;
  const auto bad_query = submit_cli(path + " -o " + dir_ + "/x.rle --analysis 'analysis?min_wall=-1' --server " + server_url());
  EXPECT_EQ(bad_query.exit_code, 2) << bad_query.err;
  EXPECT_NE(bad_query.err.find("min_wall"), std::string::npos) << bad_query.err;
}

TEST_F(SubmitCli, ErrorsExitAsVoxelizeWithTheProblemType) {
  start({"--max-voxels", "1000"});
  const std::string box = mesh_file("box.stl", to_binary_stl(make_box({0, 0, 0}, {2, 3, 4})));
  const std::string server = " --server " + server_url();
  // Parameters and formats are checked before any upload: exit 2.
  auto r = submit_cli(box + " -o " + dir_ + "/x.rle --resolution 0" + server);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/grid/resolution"), std::string::npos) << r.err;
  r = submit_cli(box + " -o " + dir_ + "/x.vox" + server);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("vox holds colours"), std::string::npos) << r.err;
  // The service's own limits: limit-exceeded exits 2 as voxelize's does.
  r = submit_cli(box + " -o " + dir_ + "/x.rle --resolution 64 --streaming off" + server);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("voxd: limit-exceeded: ", 0), 0u) << r.err;
  // A mesh the service cannot read: exit 1, its problem type first.
  const std::string broken = mesh_file("broken.stl", {'s', 'o', 'l', 'i', 'd', '\n'});
  r = submit_cli(broken + " -o " + dir_ + "/x.rle" + server);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(r.err.rfind("voxd: invalid-mesh: ", 0), 0u) << r.err;
  // No service there: exit 1.
  r = submit_cli(box + " -o " + dir_ + "/x.rle --server http://127.0.0.1:9");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(r.err.rfind("voxd: unreachable: ", 0), 0u) << r.err;
  // Issue #37, finding 9: it names the server and says what happened.
  EXPECT_NE(r.err.find("POST http://127.0.0.1:9/v1/jobs: cannot connect: the connection was refused"), std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/x.rle"));
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/x.rle.partial"));
}

// Issue #37, finding 9: an event stream that never ends an event is not
// buffered without bound: submit drops it after a MiB and polls instead.
TEST_F(SubmitCli, AnEventStreamThatNeverEndsAnEventIsDroppedForPolling) {
  const std::string id(32, 'a');
  const json done = {{"id", id}, {"state", "succeeded"}, {"progress", 1.0}, {"params", json::object()}};
  std::atomic<std::uint64_t> streamed{0};
  std::atomic<int> polls{0};
  httplib::Server stub;
  stub.Post("/v1/jobs", [&](const httplib::Request&, httplib::Response& res) {
    res.status = 202;
    res.set_content(json{{"id", id}, {"state", "queued"}}.dump(), "application/json");
  });
  stub.Get("/v1/jobs/" + id + "/events", [&](const httplib::Request&, httplib::Response& res) {
    res.set_chunked_content_provider("text/event-stream", [&](std::size_t, httplib::DataSink& sink) {
      const std::string line = "data: " + std::string(4096, 'x') + "\n";  // never a blank line
      if (streamed > (std::uint64_t{256} << 20)) return false;
      streamed += line.size();
      return sink.write(line.data(), line.size());
    });
  });
  stub.Get("/v1/jobs/" + id, [&](const httplib::Request&, httplib::Response& res) {
    ++polls;
    res.set_content(done.dump(), "application/json");
  });
  stub.Get("/v1/jobs/" + id + "/volume", [&](const httplib::Request&, httplib::Response& res) {
    res.set_content("volume-bytes", "application/octet-stream");
  });
  const int port = stub.bind_to_any_port("127.0.0.1");
  std::thread serving([&] { stub.listen_after_bind(); });
  const std::string box = mesh_file("box.stl", to_binary_stl(make_box({0, 0, 0}, {1, 1, 1})));
  const auto r = run_process("timeout 30 " + std::string(VOXD_BINARY) + " submit " + box + " -o " + dir_ +
                             "/x.rle --no-progress --server http://127.0.0.1:" + std::to_string(port));
  stub.stop();
  serving.join();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("without ending an event; polling instead"), std::string::npos) << r.err;
  EXPECT_GE(polls.load(), 1);
  EXPECT_LT(streamed.load(), std::uint64_t{16} << 20) << "submit kept reading the stream";
  EXPECT_EQ(text_of(read_file(dir_ + "/x.rle")), "volume-bytes");
}

TEST_F(SubmitCli, ATerminalGetsAProgressBarToTheEnd) {
  start();
  const std::string torus = std::string(VOXD_TEST_PARTS) + "/torus.stl";
  // util-linux's script(1) gives the command a terminal.
  const auto r = run_process("script -qec '" + std::string(VOXD_BINARY) + " submit " + torus + " -o " + dir_ +
                             "/t.rle --resolution 96 --server " + server_url() + "' /dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("\r["), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("] 100% succeeded"), std::string::npos) << r.out;
  EXPECT_EQ(text_of(read_file(dir_ + "/t.rle")), cli_volume(read_file(torus), "torus.stl", R"({"grid":{"resolution":96}})"));
  // Not a terminal: no bar.
  const auto plain = run_process(std::string(VOXD_BINARY) + " submit " + torus + " -o " + dir_ + "/t2.rle --resolution 96 --server " + server_url());
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_EQ(plain.err.find('\r'), std::string::npos) << plain.err;
}

}  // namespace
}  // namespace voxd::test
