#include "server/jobs/job_record.h"

#include "api/job_params.h"

#include <ctime>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "api/analysis_json.h"
#include "api/result_json.h"
#include "api/job_params.h"

namespace voxd::server {
namespace {

using nlohmann::json;

json time_or_null(const std::string& t) { return t.empty() ? json(nullptr) : json(t); }
std::string time_from(const json& v) { return v.is_null() ? std::string() : v.get<std::string>(); }

glm::dvec3 vec3_from(const json& v) { return {v.at(0).get<double>(), v.at(1).get<double>(), v.at(2).get<double>()}; }

MeshReport report_from_json(const json& j) {
  MeshReport r;
  r.triangles = j.at("triangles");
  r.vertices = j.at("vertices");
  r.bbox.min = vec3_from(j.at("bbox_min"));
  r.bbox.max = vec3_from(j.at("bbox_max"));
  r.degenerate_triangles = j.at("degenerate_triangles");
  r.boundary_edges = j.at("boundary_edges");
  r.nonmanifold_edges = j.at("nonmanifold_edges");
  r.inconsistent_edges = j.at("inconsistent_edges");
  r.watertight = j.at("watertight");
  r.surface_area = j.at("surface_area");
  r.volume = j.at("volume").is_null() ? 0.0 : j.at("volume").get<double>();
  if (j.contains("warnings")) r.warnings = j.at("warnings").get<std::vector<std::string>>();
  if (j.contains("orientation")) {
    const json& o = j.at("orientation");
    OrientationRepair& repair = r.orientation.emplace();
    repair.components = o.at("components");
    repair.inconsistent_edges = o.at("inconsistent_edges");
    repair.flipped_triangles = o.at("flipped_triangles");
    repair.inconsistent_triangles = o.at("inconsistent_triangles");
    repair.inverted_components = o.at("inverted_components");
    repair.unorientable_edges = o.at("unorientable_edges");
    repair.boundary_edges = r.boundary_edges;
    repair.nonmanifold_edges = r.nonmanifold_edges;
  }
  return r;
}

Grid grid_from_json(const json& j) {
  Grid g;
  g.origin = vec3_from(j.at("origin"));
  g.voxel_size = j.at("voxel_size");
  g.dims = {j.at("dims").at(0).get<std::int64_t>(), j.at("dims").at(1).get<std::int64_t>(),
            j.at("dims").at(2).get<std::int64_t>()};
  return g;
}


}  // namespace

std::string format_time(std::chrono::system_clock::time_point t) {
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(t.time_since_epoch()).count();
  const std::time_t secs = static_cast<std::time_t>(ms / 1000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char buf[40];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  char out[48];
  std::snprintf(out, sizeof out, "%s.%03dZ", buf, static_cast<int>(ms % 1000));
  return out;
}

std::chrono::system_clock::time_point parse_time(const std::string& text) {
  std::tm tm{};
  int millis = 0;
  std::istringstream in(text);
  in >> std::get_time(&tm, "%Y-%m-%dT%H:%M:%S");
  if (in.fail()) throw std::invalid_argument("bad time '" + text + "'");
  char dot = 0;
  if (in >> dot && dot == '.') in >> millis;
  return std::chrono::system_clock::from_time_t(timegm(&tm)) + std::chrono::milliseconds(millis);
}

std::optional<JobState> job_state_from_string(const std::string& name) {
  return value_named(kJobStateNames, name);
}

json record_json(const JobSnapshot& job) {
  json out = {
      {"id", job.id},
      {"state", to_string(job.state)},
      {"progress", job.progress},
      {"stage", job.state == JobState::running && !job.stage.empty() ? json(job.stage) : json(nullptr)},
      {"created_at", time_or_null(job.created_at)},
      {"started_at", time_or_null(job.started_at)},
      {"finished_at", time_or_null(job.finished_at)},
      {"params", job.params},
      {"mesh", job.mesh ? api::to_json(*job.mesh) : json(nullptr)},
      {"mesh_format", job.mesh_format},
      {"triangles", job.triangles},
      {"grid", api::to_json(job.grid)},
      {"cached", job.cached},
      {"streamed", job.streamed},
      {"execution", to_string(job.execution)},
      {"content_hash", job.content_hash},
      {"inside", job.inside ? api::to_json(*job.inside) : json(nullptr)},
      // The mesh file's unit, as given; every length here is in millimetres.
      {"units", {{"mesh", job.job ? to_string(job.job->units) : "mm"}, {"lengths", "mm"}}},
      {"warnings", api::to_json(job.warnings)},
      {"name", job.labels.name},
      {"tenant", job.labels.tenant.empty() ? json(nullptr) : json(job.labels.tenant)},
      {"callback", job.labels.callback.empty() ? json(nullptr) : json(job.labels.callback)},
      {"stored_bytes", job.stored_bytes},
  };
  json tags = json::object();
  for (const auto& [key, value] : job.labels.tags) tags[key] = value;
  out["tags"] = tags;
  json timings = json::object();
  for (const auto& [stage, seconds] : job.timings) timings[stage] = seconds;
  out["timings"] = timings;
  out["analyses"] = job.analyses;
  out["values"] = job.values;
  if (job.filled_voxels) {
    out["filled_voxels"] = *job.filled_voxels;
    out["filled_volume"] = static_cast<double>(*job.filled_voxels) * job.grid.voxel_volume();
  } else {
    out["filled_voxels"] = nullptr;
    out["filled_volume"] = nullptr;
  }
  if (job.failure) {
    out["error"] = {{"type", "urn:voxd:problem:" + job.failure->type},
                    {"title", job.failure->title},
                    {"detail", job.failure->detail}};
  } else {
    out["error"] = nullptr;
  }
  return out;
}

JobSnapshot job_from_json(const json& r) {
  JobSnapshot job;
  job.id = r.at("id");
  const auto state = job_state_from_string(r.at("state").get<std::string>());
  if (!state) throw std::invalid_argument("unknown state");
  job.state = *state;
  job.progress = r.at("progress");
  job.created_at = time_from(r.at("created_at"));
  job.started_at = time_from(r.at("started_at"));
  job.finished_at = time_from(r.at("finished_at"));
  job.params = r.at("params");
  // Recorded by this service, so it parses; the mode comes from it once.
  job.job = std::make_shared<const api::JobParams>(api::parse_job_params(job.params));
  if (!r.at("mesh").is_null()) job.mesh = report_from_json(r.at("mesh"));
  if (r.contains("mesh_mass")) {
    const json& m = r.at("mesh_mass");
    MassProperties p;
    p.volume = m.at("volume");
    p.centroid = vec3_from(m.at("centroid"));
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) p.inertia[col][row] = m.at("inertia").at(row).at(col).get<double>();
    p.bbox.min = vec3_from(m.at("bbox_min"));
    p.bbox.max = vec3_from(m.at("bbox_max"));
    job.mesh_mass = p;
  }
  job.mesh_format = r.at("mesh_format");
  job.triangles = r.at("triangles");
  job.grid = grid_from_json(r.at("grid"));
  for (const auto& [stage, seconds] : r.at("timings").items()) job.timings.emplace_back(stage, seconds.get<double>());
  if (!r.at("filled_voxels").is_null()) job.filled_voxels = r.at("filled_voxels").get<std::uint64_t>();
  if (!r.at("error").is_null()) {
    const std::string type = r.at("error").at("type");
    const std::string prefix = "urn:voxd:problem:";
    job.failure = JobFailure{type.rfind(prefix, 0) == 0 ? type.substr(prefix.size()) : type,
                             r.at("error").at("title"), r.at("error").at("detail")};
  }
  if (r.contains("analyses") && r.at("analyses").is_array()) job.analyses = r.at("analyses");
  if (r.contains("values") && r.at("values").is_object()) job.values = r.at("values");
  // Records of earlier releases have neither.
  if (r.contains("inside") && r.at("inside").is_object()) job.inside = api::inside_choice_from_json(r.at("inside"));
  if (r.contains("warnings")) job.warnings = api::warnings_from_json(r.at("warnings"));
  job.cached = r.at("cached");
  job.streamed = r.value("streamed", false);  // records of earlier releases have none
  // Records of earlier releases have none: they ran slab by slab or in memory.
  const std::optional<ExecutionPath> path = value_named(kExecutionPathNames, r.value("execution", std::string()));
  job.execution = path ? *path : job.streamed ? ExecutionPath::slabs : ExecutionPath::memory;
  job.content_hash = r.at("content_hash");
  // Records of earlier releases have no labels: no tenant, no name.
  job.labels.name = r.value("name", std::string());
  if (r.contains("tenant") && r.at("tenant").is_string()) job.labels.tenant = r.at("tenant");
  if (r.contains("callback") && r.at("callback").is_string()) job.labels.callback = r.at("callback");
  if (r.contains("tags") && r.at("tags").is_object())
    for (const auto& [key, value] : r.at("tags").items()) job.labels.tags.emplace_back(key, value.get<std::string>());
  job.stored_bytes = r.value("stored_bytes", std::uint64_t{0});
  return job;
}

nlohmann::json stored_record(const JobSnapshot& job) {
  nlohmann::json record = record_json(job);
  if (job.mesh_mass) record["mesh_mass"] = api::to_json(*job.mesh_mass);
  return record;
}

}  // namespace voxd::server
