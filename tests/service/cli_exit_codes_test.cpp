// The CLI's exit status for every engine error code: the README's table, the
// one error table (api/error_table.h) and a real `voxd` process that hits the
// error must all agree.
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>

#include "api/error_table.h"
#include "support/run_process.h"
#include "support/test_meshes.h"

namespace voxd {
namespace {

struct ReadmeRow {
  int exit = -1;
  std::string slug;
  int status = 0;
};

// "| `code` | exit | `slug` | status |" rows of README.md.
std::map<std::string, ReadmeRow> readme_table() {
  std::ifstream in(std::string(VOXD_SOURCE_DIR) + "/README.md");
  std::stringstream text;
  text << in.rdbuf();
  const std::string readme = text.str();
  const std::regex row(R"(\| `([a-z_]+)` \| ([0-9]) \| `([a-z-]+)` \| ([0-9]{3}) \|)");
  std::map<std::string, ReadmeRow> rows;
  for (std::sregex_iterator it(readme.begin(), readme.end(), row), end; it != end; ++it)
    rows[(*it)[1]] = {std::stoi((*it)[2]), (*it)[3], std::stoi((*it)[4])};
  return rows;
}

TEST(CliExitCodes, TheReadmeListsEveryCodeAsTheErrorTableDoes) {
  const auto readme = readme_table();
  EXPECT_EQ(readme.size(), api::error_table().size());
  for (const api::ErrorKind& kind : api::error_table()) {
    const std::string code = to_string(kind.code);
    ASSERT_TRUE(readme.count(code)) << code << " is missing from README.md's table";
    EXPECT_EQ(readme.at(code).exit, kind.cli_exit) << code;
    EXPECT_EQ(readme.at(code).slug, kind.slug) << code;
    EXPECT_EQ(readme.at(code).status, kind.http_status) << code;
    // The README's rule: 2 for what the caller asked wrongly, 1 otherwise.
    const bool request_error = kind.code == ErrorCode::invalid_argument || kind.code == ErrorCode::limit_exceeded;
    EXPECT_EQ(kind.cli_exit, request_error ? 2 : 1) << code;
    EXPECT_EQ(api::error_kind(kind.code).code, kind.code);
  }
}

class CliExitCodeTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::make_temp_dir("voxd-exit"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& bytes) {
    test::write_file(dir_ + "/" + name, std::vector<std::uint8_t>(bytes.begin(), bytes.end()));
    return dir_ + "/" + name;
  }
  std::string dir_;
};

std::string ascii_stl(const std::string& vertices) {
  return "solid t\nfacet normal 0 0 1\nouter loop\n" + vertices + "endloop\nendfacet\nendsolid t\n";
}

std::string binary_stl_header(std::uint32_t declared_triangles, std::size_t body_bytes) {
  std::string s(80, '\0');
  for (int i = 0; i < 4; ++i) s.push_back(static_cast<char>((declared_triangles >> (8 * i)) & 0xff));
  return s + std::string(body_bytes, '\0');
}

TEST_F(CliExitCodeTest, EveryCodeTheCliCanHitExitsAsTheTableSays) {
  const std::string voxd = VOXD_BINARY;
  const std::string box = dir_ + "/box.stl";
  test::write_file(box, test::to_binary_stl(test::make_box({0, 0, 0}, {1, 1, 1})));
  const std::string out = " -o " + dir_ + "/out.rle";
  // One real way to hit each code from the command line.
  const std::map<ErrorCode, std::string> commands = {
      {ErrorCode::invalid_argument, "voxelize " + box + out + " --voxel-size 1e-9"},
      {ErrorCode::empty_input, "inspect " + write("empty.stl", "")},
      {ErrorCode::truncated_input, "inspect " + write("cut.stl", binary_stl_header(10, 60))},
      {ErrorCode::malformed_input, "inspect " + write("bad.stl", ascii_stl("vertex 0 0 x\nvertex 1 0 0\nvertex 0 1 0\n"))},
      {ErrorCode::non_finite_coordinates,
       "inspect " + write("nan.stl", ascii_stl("vertex 0 0 0\nvertex nan 0 0\nvertex 0 1 0\n"))},
      {ErrorCode::no_usable_triangles, "inspect " + write("none.stl", binary_stl_header(0, 0))},
      {ErrorCode::unknown_format, "inspect " + write("x.bin", "hello world, not a mesh at all\n")},
      {ErrorCode::limit_exceeded, "voxelize " + box + out + " --resolution 100 --max-voxels 1000"},
      {ErrorCode::io_error, "inspect " + dir_ + "/missing.stl"},
  };
  for (const api::ErrorKind& kind : api::error_table()) {
    const std::string code = to_string(kind.code);
    if (kind.code == ErrorCode::cancelled) {
      // Only a client's cancel of a running service job raises it.
      EXPECT_FALSE(commands.count(kind.code));
      continue;
    }
    ASSERT_TRUE(commands.count(kind.code)) << "no CLI reproducer for " << code;
    const auto r = test::run_process(voxd + " " + commands.at(kind.code));
    EXPECT_EQ(r.exit_code, kind.cli_exit) << code << ": " << r.err;
    EXPECT_EQ(r.err.rfind("voxd: " + code + ": ", 0), 0u) << code << ": " << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/out.rle"));
}

}  // namespace
}  // namespace voxd
