#pragma once
// The job JSON of the voxelize and analyze commands: --params JSON|@FILE, then
// the grid and mode flags applied onto it, so one validator reports errors
// for both with JSON paths.
#include <nlohmann/json.hpp>

#include "server/cli/cli_args.h"

namespace voxd::cli {

nlohmann::json load_params(const Args& args);
void apply_param_flags(const Args& args, nlohmann::json& params);

// --threads N (1..1024), 0 when absent (all cores).
int thread_count(const Args& args);

// The flags apply_param_flags reads (each takes a value).
inline const char* const kParamFlags[] = {"params", "resolution", "voxel-size", "origin", "dims", "padding", "mode", "inside", "units"};

}  // namespace voxd::cli
