#include "server/cli/cli.h"

#include <cstring>
#include <iostream>
#include <string>

#include "api/error_table.h"
#include "api/param_error.h"
#include "server/cli/cli_args.h"
#include "server/draco_isolation.h"
#include "voxd/error.h"

namespace voxd::cli {
namespace {

constexpr const char* kUsage = R"(voxd: voxelization engine and service

usage:
  voxd inspect MESH                    mesh report as JSON
  voxd voxelize MESH -o OUT [options]  voxelize to rle / binvox / raw
  voxd analyze MESH -o DIR [options]   manufacturing analysis into DIR (analysis.json)
  voxd submit MESH -o OUT [options]    run the job on a voxd service (--server URL)
  voxd serve [options]                 the HTTP service (voxd serve --help)
  voxd devices [--json]                the GPUs it can compute on, or why none
  voxd --version

Run 'voxd COMMAND --help' for a command's options.
)";

}  // namespace

int run(int argc, char** argv) {
  try {
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
      std::cout << kUsage;
      return argc < 2 ? 2 : 0;
    }
    const std::string command = argv[1];
    if (command == "--version") {
      std::cout << "voxd " << VOXD_VERSION << '\n';
      return 0;
    }
    if (command == "inspect") return inspect_command(argc, argv);
    if (command == "voxelize") return voxelize_command(argc, argv);
    if (command == "analyze") return analyze_command(argc, argv);
    if (command == "submit") return submit_command(argc, argv);
    if (command == "serve") return serve_command(argc, argv);
    if (command == "devices") return devices_command(argc, argv);
    // Internal: the service's isolated Draco decoder (server/draco_isolation.h).
    if (command == "decode-draco-isolated") return server::decode_draco_child(argc, argv);
    throw UsageError("unknown command '" + command + "' (try voxd --help)");
  } catch (const UsageError& e) {
    std::cerr << "voxd: " << e.what() << '\n';
    return api::kExitUsage;
  } catch (const api::InvalidParams& e) {
    std::cerr << "voxd: " << e.what() << '\n';
    return api::kExitUsage;
  } catch (const Error& e) {
    std::cerr << "voxd: " << to_string(e.code()) << ": " << e.what() << '\n';
    return api::error_kind(e.code()).cli_exit;
  } catch (const std::exception& e) {
    std::cerr << "voxd: internal error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace voxd::cli
