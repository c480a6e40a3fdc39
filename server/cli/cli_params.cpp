#include "server/cli/cli_params.h"

#include <string>

#include "api/bounded_json.h"
#include "voxd/encode/number_text.h"

namespace voxd::cli {

using nlohmann::json;

json load_params(const Args& args) {
  auto text = args.value("params");
  if (!text) return json::object();
  std::string body = *text;
  if (!body.empty() && body[0] == '@') body = read_text_file(body.substr(1));
  try {
    return api::parse_bounded_json(body, "--params");
  } catch (const api::InvalidJson& e) {
    throw UsageError(e.what());
  }
}

// Flags are applied onto the JSON document so one validator reports errors
// for both, with JSON paths.
void apply_param_flags(const Args& args, json& params) {
  if (!params.is_object()) return;  // the validator reports it
  auto grid_flag = [&](const char* flag) { return args.value(flag); };
  const bool any_grid = grid_flag("resolution") || grid_flag("voxel-size") || grid_flag("origin") ||
                        grid_flag("dims") || grid_flag("padding");
  if (any_grid) {
    json& grid = params["grid"];
    if (!grid.is_object()) grid = json::object();
    auto integer = [](const std::string& flag, const std::string& v) {
      if (const auto n = parse_number<long long>(v)) return *n;
      throw UsageError("--" + flag + " expects an integer, got '" + v + "'");
    };
    if (auto v = grid_flag("resolution")) {
      grid.erase("voxel_size");
      grid.erase("origin");
      grid.erase("dims");
      grid["resolution"] = integer("resolution", *v);
    }
    if (auto v = grid_flag("voxel-size")) {
      grid.erase("resolution");
      grid["voxel_size"] = parse_number_list(*v, 1, "voxel-size")[0];
    }
    if (auto v = grid_flag("origin")) {
      grid.erase("resolution");
      grid.erase("padding");
      grid["origin"] = parse_number_list(*v, 3, "origin");
    }
    if (auto v = grid_flag("dims")) {
      grid.erase("resolution");
      grid.erase("padding");
      const auto d = parse_number_list(*v, 3, "dims");
      grid["dims"] = json::array();
      for (double x : d) {
        if (x != static_cast<double>(static_cast<long long>(x))) throw UsageError("--dims expects integers");
        grid["dims"].push_back(static_cast<long long>(x));
      }
    }
    if (auto v = grid_flag("padding")) grid["padding"] = integer("padding", *v);
  }
  if (auto v = args.value("mode")) params["mode"] = *v;
  if (auto v = args.value("inside")) params["inside"] = *v;
  if (auto v = args.value("units")) params["units"] = *v;
  if (auto v = args.value("device")) params["device"] = *v;
}

int thread_count(const Args& args) {
  const auto t = args.value("threads");
  if (!t) return 0;
  const std::optional<int> threads = parse_number<int>(*t);
  if (!threads || *threads < 1 || *threads > 1024) throw UsageError("--threads must be between 1 and 1024");
  return *threads;
}

}  // namespace voxd::cli
