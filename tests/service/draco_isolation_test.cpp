// The isolated Draco decoder's parent side against children that crash,
// hang, exit without an answer or answer garbage (stand-in executables made
// here), and against the real child on real and hostile files.
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "server/draco_isolation.h"
#include "support/draco_cli.h"
#include "support/run_process.h"
#include "support/test_meshes.h"
#include "voxd/error.h"

namespace voxd::server {
namespace {

class DracoIsolationTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::make_temp_dir("voxd-draco-iso"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // A stand-in child: a shell script.
  std::string script(const std::string& name, const std::string& body) {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path) << "#!/bin/sh\n" << body << "\n";
    ::chmod(path.c_str(), 0755);
    return path;
  }

  // The decoder's failure message for this child, or "" if it returned.
  std::string failure(const DracoIsolation& iso, const std::vector<std::uint8_t>& data = {'D', 'R', 'A', 'C', 'O'}) {
    try {
      decode_draco_isolated(data, iso);
      return "";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::malformed_input) << e.what();
      return e.what();
    }
  }

  std::string dir_;
};

TEST_F(DracoIsolationTest, ACrashingChildIsAnInvalidFileNotACrash) {
  DracoIsolation iso;
  iso.executable = script("crash", "cat >/dev/null; kill -SEGV $$");
  EXPECT_NE(failure(iso).find("crashed (Segmentation fault)"), std::string::npos) << failure(iso);
}

TEST_F(DracoIsolationTest, AHangingChildIsStoppedAtTheDeadline) {
  DracoIsolation iso;
  iso.executable = script("hang", "exec sleep 30");
  iso.deadline = std::chrono::seconds(1);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_NE(failure(iso).find("took longer than 1 s"), std::string::npos);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
}

TEST_F(DracoIsolationTest, GarbageOrNoAnswerIsRefused) {
  DracoIsolation iso;
  iso.executable = script("silent", "cat >/dev/null; exit 0");
  EXPECT_NE(failure(iso).find("gave no answer"), std::string::npos);
  iso.executable = script("liar", "cat >/dev/null; printf 'VXM1\\001\\000\\000\\000\\000\\000\\000\\000'; exit 0");
  EXPECT_NE(failure(iso).find("gave no answer"), std::string::npos);
  iso.executable = script("failing", "cat >/dev/null; exit 7");
  EXPECT_NE(failure(iso).find("ended with status 7"), std::string::npos);
}

TEST_F(DracoIsolationTest, TheRealChildDecodesLikeTheInProcessDecoder) {
  ASSERT_TRUE(test::draco_encoder_available());
  const std::vector<std::uint8_t> drc = test::encode_with_draco_encoder(test::make_icosphere({0, 0, 0}, 1, 3), "");
  DracoIsolation iso;
  iso.executable = VOXD_BINARY;
  const Mesh isolated = decode_draco_isolated(drc, iso);
  const Mesh direct = decode_mesh_as(MeshFormat::draco, drc);
  EXPECT_EQ(isolated.vertices, direct.vertices);
  EXPECT_EQ(isolated.triangles, direct.triangles);
  // A cut-off file is reported in the child's own words.
  const std::vector<std::uint8_t> cut(drc.begin(), drc.begin() + static_cast<std::ptrdiff_t>(drc.size() / 2));
  try {
    decode_draco_isolated(cut, iso);
    ADD_FAILURE() << "a cut-off file decoded";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("Draco"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace voxd::server
