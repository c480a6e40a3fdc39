#pragma once
// `voxd serve`'s settings from its flags, each also settable as VOXD_<NAME>
// in the environment (flags win), over the embedded defaults
// (server/http/server_config.h).
#include <string>

#include "server/http/server_config.h"

namespace voxd::cli {

// Parses argv[first..] over the environment over the defaults. Throws
// UsageError with a message naming the flag or variable.
server::ServeConfig parse_serve_config(int argc, char** argv, int first);
std::string serve_help();

}  // namespace voxd::cli
