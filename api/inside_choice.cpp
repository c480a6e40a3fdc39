#include "api/inside_choice.h"

#include <string>

namespace voxd::api {
namespace {

std::string count_of(std::uint64_t n, const char* what) { return std::to_string(n) + " " + what; }

}  // namespace

InsideChoice choose_inside_test(const JobParams& params, const EdgeTopology* topology) {
  InsideChoice choice;
  choice.test = params.inside;
  if (!params.mode->uses_inside_test()) {
    choice.reason = "mode " + params.mode_name() + " counts crossings along rays (parity) whatever the mesh";
    return choice;
  }
  if (!params.inside_auto) return choice;
  if (!topology) throw std::logic_error("\"inside\": \"auto\" needs the mesh's topology");
  choice.automatic = true;
  if (topology->closed()) {
    choice.test = InsideTest::parity;
    choice.reason = "the mesh is closed: parity, exact and fastest";
    return choice;
  }
  std::string why;
  auto add = [&why](const std::string& part) { why += (why.empty() ? "" : ", ") + part; };
  if (topology->boundary_edges) add(count_of(topology->boundary_edges, "boundary edges"));
  if (topology->nonmanifold_edges) add(count_of(topology->nonmanifold_edges, "non-manifold edges"));
  choice.test = InsideTest::winding;
  choice.reason = "the mesh is not closed (" + why +
                  "): the generalized winding number, which does not leak through holes as parity does";
  return choice;
}

nlohmann::json to_json(const InsideChoice& c) {
  nlohmann::json out = {{"test", to_string(c.test)}, {"chosen", c.automatic ? "auto" : "asked"}};
  if (!c.reason.empty()) out["reason"] = c.reason;
  return out;
}

InsideChoice inside_choice_from_json(const nlohmann::json& j) {
  InsideChoice c;
  c.test = value_named(kInsideTestNames, j.at("test").get<std::string>()).value_or(InsideTest::parity);
  c.automatic = j.at("chosen") == "auto";
  c.reason = j.value("reason", "");
  return c;
}

}  // namespace voxd::api
