// `voxd devices`: the GPUs this voxd can compute on (voxd/compute_device.h),
// to check a machine before asking for "device": "cuda".
#include <iostream>

#include <nlohmann/json.hpp>

#include "server/cli/cli.h"
#include "server/cli/cli_args.h"
#include "voxd/compute_device.h"

namespace voxd::cli {

int devices_command(int argc, char** argv) {
  Args args(argc, argv, 2, {}, {"json", "help"});
  if (args.has("help")) {
    std::cout << "usage: voxd devices [--json]\n\nLists the CUDA GPUs this voxd can compute on (a slice job's colours with\n"
                 "\"device\": \"auto\" or \"cuda\"), or says why there are none: a build without the\n"
                 "CUDA backend, no driver, no GPU, or CUDA_VISIBLE_DEVICES hiding them. Exits 0\n"
                 "either way; --json prints {\"cuda_built\", \"gpus\": [{name, memory_bytes,\n"
                 "compute}], \"cuda_unavailable\": reason or null}.\n";
    return 0;
  }
  if (!args.positional().empty()) throw UsageError("devices takes no arguments (see voxd devices --help)");
  const std::string& why = cuda_unavailable_reason();
  if (args.has("json")) {
    nlohmann::json gpus = nlohmann::json::array();
    for (const GpuInfo& g : cuda_devices())
      gpus.push_back({{"name", g.name},
                      {"memory_bytes", g.memory_bytes},
                      {"compute", std::to_string(g.compute_major) + "." + std::to_string(g.compute_minor)}});
    std::cout << nlohmann::json{{"cuda_built", cuda_built()},
                                {"gpus", gpus},
                                {"cuda_unavailable", why.empty() ? nlohmann::json() : nlohmann::json(why)}}
                     .dump()
              << '\n';
    return 0;
  }
  std::cout << "cpu: yes\n";
  for (const GpuInfo& g : cuda_devices())
    std::cout << "cuda: " << g.name << ", " << (g.memory_bytes >> 20) << " MiB, compute " << g.compute_major << '.'
              << g.compute_minor << '\n';
  if (!why.empty()) std::cout << "cuda: none (" << why << ")\n";
  return 0;
}

}  // namespace voxd::cli
