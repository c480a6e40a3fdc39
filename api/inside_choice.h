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
#include "voxd/mesh_orientation.h"

namespace voxd::api {

struct InsideChoice {
  InsideTest test = InsideTest::parity;
  bool automatic = false;  // chosen from the mesh
  std::string reason;      // why this test, in words; empty when asked for by name
};

// The job's choice. `topology` is what orienting the mesh saw; it is read
// only for "auto" and must then be given.
InsideChoice choose_inside_test(const JobParams& params, const OrientationRepair* topology);

// Whether the job's mesh must be oriented before it is voxelized: the
// winding number (asked for, or possibly chosen) counts a triangle's side.
inline bool orients_mesh(const JobParams& params) {
  return params.mode->uses_inside_test() && (params.inside_auto || params.inside == InsideTest::winding);
}

// {"test", "chosen": "auto" | "asked", "reason"}: the job status's and the report's "inside".
nlohmann::json to_json(const InsideChoice& choice);
InsideChoice inside_choice_from_json(const nlohmann::json& j);

}  // namespace voxd::api
