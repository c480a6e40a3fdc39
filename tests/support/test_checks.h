#pragma once
// Checks the unit tests share: the voxd::Error a call throws, PNG bytes as an
// independent reader (tests/tools/read_png.py) decodes them, and the camera
// table of the six axis views written out apart from the implementation.
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/run_process.h"
#include "support/test_meshes.h"
#include "voxd/error.h"
#include "voxd/analysis/preview.h"

namespace voxd::test {

// The code of the voxd::Error `f` throws, its message into `message`; fails
// the test when it throws none.
inline ErrorCode code_of(const std::function<void()>& f, std::string* message = nullptr) {
  try {
    f();
  } catch (const Error& e) {
    if (message) *message = e.what();
    return e.code();
  }
  ADD_FAILURE() << "no voxd::Error thrown";
  return ErrorCode::io_error;
}

// {width, height, bit_depth, color_type, text: {...}, pixels: [samples]}
// (with `checksum`, sample_count and sample_sum instead of pixels); fails the
// test, and returns {}, when the reader refuses the bytes.
inline nlohmann::json decode_png(const std::vector<std::uint8_t>& png, bool checksum = false) {
  static int serial = 0;
  const std::string path = (std::filesystem::path(::testing::TempDir()) /
                            ("voxd_png_" + std::to_string(::getpid()) + "_" + std::to_string(serial++) + ".png"))
                               .string();
  write_file(path, png);
  const ProcessResult r = run_process(std::string("/usr/bin/python3 ") + VOXD_SOURCE_DIR + "/tests/tools/read_png.py " +
                                      path + (checksum ? " --checksum" : ""));
  std::filesystem::remove(path);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  if (r.exit_code != 0) return nlohmann::json::object();
  return nlohmann::json::parse(r.out);
}

// The six axis views: camera side, and the image's right and up axes with
// their signs, as preview.h documents them.
struct ViewCase {
  const char* name;
  int axis;
  bool from_positive;
  int right_axis, right_sign, up_axis, up_sign;
};
inline constexpr ViewCase kViews[] = {
    {"+z", 2, true, 0, +1, 1, +1}, {"-z", 2, false, 0, -1, 1, +1}, {"+x", 0, true, 1, +1, 2, +1},
    {"-x", 0, false, 1, -1, 2, +1}, {"+y", 1, true, 0, -1, 2, +1}, {"-y", 1, false, 0, +1, 2, +1},
};
inline View view_of(const ViewCase& v) { return View{v.axis, v.from_positive}; }

// Directions of a view written out from the table, apart from the
// implementation: along +-axis, the camera's forward, and the light the
// shaded previews use (from the camera, up and to the left).
template <typename Vec>
Vec unit(int axis, int sign) {
  Vec u(0);
  u[axis] = static_cast<typename Vec::value_type>(sign);
  return u;
}
template <typename Vec>
Vec forward(const ViewCase& v) {
  return unit<Vec>(v.axis, v.from_positive ? -1 : +1);
}
template <typename Vec>
Vec light(const ViewCase& v) {
  using T = typename Vec::value_type;
  return glm::normalize(-forward<Vec>(v) + T(0.5) * unit<Vec>(v.up_axis, v.up_sign) -
                        T(0.35) * unit<Vec>(v.right_axis, v.right_sign));
}

}  // namespace voxd::test
