#pragma once
// Runs a shell command and captures its exit code, stdout and stderr (tests).
#include <string>

namespace voxd::test {

struct ProcessResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

ProcessResult run_process(const std::string& command);
// A fresh empty temporary directory, removed by the caller if it wants.
std::string make_temp_dir(const std::string& prefix);

}  // namespace voxd::test
