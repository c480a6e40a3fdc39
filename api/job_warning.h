#pragma once
// A warning on a job: a result the user should doubt, or a choice made for
// them, with what to do about it. Part of the contract (the job status, the
// report and `voxd voxelize --json` carry a "warnings" list of them): the
// code is stable for programs, the message is for people, the details are
// the numbers behind it.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/inside_choice.h"
#include "api/job_params.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/mesh_orientation.h"

namespace voxd::api {

struct JobWarning {
  std::string code;
  std::string message;
  nlohmann::json details = nlohmann::json::object();
};

nlohmann::json to_json(const std::vector<JobWarning>& warnings);
std::vector<JobWarning> warnings_from_json(const nlohmann::json& list);

// What preparing a job found doubtful: the inside test against the mesh's
// topology, what orienting it turned round, a part whose size suggests the
// wrong unit, a voxel larger than the part. `box` is the mesh's bounds in
// millimetres; `repair` is null when the mesh was not oriented.
std::vector<JobWarning> prepared_job_warnings(const JobParams& params, const InsideChoice& inside,
                                              const OrientationRepair* repair, const Aabb& box, const Grid& grid);

// Parity or vote, asked for by name or fixed by the mode, on a mesh that is
// not closed: their crossings leak through holes.
std::optional<JobWarning> leaky_inside_warning(const InsideChoice& inside, std::uint64_t boundary_edges,
                                               std::uint64_t nonmanifold_edges);

// A solid left empty by a mesh with area: the likely cause and what to try.
// Nullopt when something was filled, the mesh has no area or the mode
// fills only the surface.
std::optional<JobWarning> empty_result_warning(const JobParams& params, const InsideChoice& inside,
                                               std::uint64_t filled, double surface_area);

}  // namespace voxd::api
