#pragma once
// Which inside test a job's solid is made with, and why: asked for by name,
// or chosen from the mesh by "inside": "auto". Parity is exact and fastest
// on a closed, consistently oriented mesh, and leaks along whole rows
// through any hole; the generalized winding number does not leak (it is a
// smooth function across holes), needs outward triangles (which
// orient_outward gives) and the whole grid in memory.
#include <string>

#include <nlohmann/json.hpp>

#include "api/job_params.h"
#include "voxd/edge_topology.h"

namespace voxd::api {

struct InsideChoice {
  InsideTest test = InsideTest::parity;
  bool automatic = false;  // chosen from the mesh
  std::string reason;      // why this test, in words; empty when asked for by name
};

// The job's choice. `topology` is the mesh's edge topology
// (count_edge_topology); it is read only for "auto" and must then be given.
// Parity where the mesh is closed (an inconsistent or inside-out closed
// mesh too: parity does not read a triangle's side), else the winding number.
InsideChoice choose_inside_test(const JobParams& params, const EdgeTopology* topology);

// Whether the job must know its mesh's edge topology before it is planned:
// "auto" chooses from it.
inline bool needs_topology(const JobParams& params) { return params.mode->uses_inside_test() && params.inside_auto; }

// {"test", "chosen": "auto" | "asked", "reason"}: the job status's and the report's "inside".
nlohmann::json to_json(const InsideChoice& choice);
InsideChoice inside_choice_from_json(const nlohmann::json& j);

}  // namespace voxd::api
