// libFuzzer harness for the job parameters: bounded JSON parsing and the
// validator. Every input is a JobParams or an InvalidParams naming paths;
// the rendered messages are read, so a value they quote is rendered too.
#include <cstdint>
#include <string>

#include "api/job_params.h"
#include "api/param_error.h"
#include "voxd/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const voxd::api::JobParams params = voxd::api::parse_job_params_text(text);
    (void)params.mode_name();
  } catch (const voxd::api::InvalidParams& e) {
    std::size_t total = 0;
    for (const auto& f : e.errors()) total += f.path.size() + f.message.size();
    if (total == 0) __builtin_trap();  // an error must say what is wrong
  } catch (const voxd::Error&) {
  }
  return 0;
}
