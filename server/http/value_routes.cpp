#include "server/http/value_routes.h"

#include <string>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "api/job_params.h"
#include "server/http/problem.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/palette_export.h"
#include "voxd/voxelize/palette_geometry.h"
#include "voxd/voxelize/palette_render.h"
#include "voxd/encode/png_stack.h"

namespace voxd::server {
namespace {

using httplib::Request;
using httplib::Response;
using nlohmann::json;

ProblemError unknown_job(const std::string& id) {
  return ProblemError(make_problem(404, "not-found", "Unknown job", "no job with id " + id + " (it may have expired or been deleted)"));
}

ProblemError invalid_query(const std::string& detail) {
  return ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", detail));
}

JobSnapshot succeeded_job(JobManager& jobs, const std::string& id) {
  const auto job = jobs.get(id);
  if (!job) throw unknown_job(id);
  if (job->state != JobState::succeeded)
    throw ProblemError(make_problem(409, "job-not-finished", "The job has no result yet",
                                    std::string("the job is ") + to_string(job->state) + "; its result exists once it has succeeded"));
  return *job;
}

ProblemError wrong_mode(const JobSnapshot& job, const std::string& what, const char* mode) {
  return ProblemError(make_problem(409, "wrong-mode", "Not available for this job's mode",
                                   what + " exists for jobs with \"mode\": \"" + mode + "\"; this job's mode is " +
                                       api::parse_job_params(job.params).mode_name()));
}

json element_json(const PaletteElement& e, std::size_t index) {
  json pieces = json::array();
  for (const ConvexPiece& piece : e.pieces) {
    json halves = json::array();
    for (const HalfSpace& h : piece) halves.push_back({h.normal.x, h.normal.y, h.normal.z, h.offset});
    pieces.push_back(std::move(halves));
  }
  return {{"index", index}, {"name", e.name}, {"pieces", std::move(pieces)}, {"volume", element_volume(e)}};
}

}  // namespace

std::shared_ptr<const ValueVolume> palette_layer(JobManager& jobs, const JobSnapshot& job, const std::string& layer) {
  const api::JobParams params = api::parse_job_params(job.params);
  if (!params.palette)
    throw invalid_query("layer selects a palette job's element, similarity or display volume; this job's mode is " +
                        params.mode_name());
  if (layer != "element" && layer != "similarity" && layer != "display")
    throw invalid_query("layer must be element, similarity or display, got '" + layer + "'");
  auto element = jobs.values(job.id);
  if (!element) throw unknown_job(job.id);
  if (layer == "element") return element;
  auto similarity = jobs.similarity(job.id);
  if (!similarity) throw unknown_job(job.id);
  if (layer == "similarity") return std::make_shared<const ValueVolume>(*similarity);
  if (params.palette->render.empty())
    throw invalid_query("layer display needs a rendering palette: the job JSON's \"palette\": {\"render\": ...}");
  return std::make_shared<const ValueVolume>(
      render_palette(std::get<DenseVolume<std::uint8_t>>(*element), *similarity, params.palette->render));
}

std::vector<std::string> install_value_routes(httplib::Server& server, JobManager& jobs, const std::string& job_path,
                                              const Guard& guarded) {
  const std::string palette_path = job_path + "/palette";
  server.Get(palette_path, guarded([&jobs](const Request& req, Response& res) {
    const JobSnapshot job = succeeded_job(jobs, req.matches[1]);
    const api::JobParams params = api::parse_job_params(job.params);
    if (!params.palette) throw wrong_mode(job, "the palette", "palette");
    const api::PaletteParams& p = *params.palette;
    auto values = jobs.values(job.id);
    if (!values) throw unknown_job(job.id);
    const auto& element = std::get<DenseVolume<std::uint8_t>>(*values);
    std::vector<std::uint64_t> counts(p.options.palette.elements.size(), 0);
    for (std::uint8_t e : element.values())
      if (e < counts.size()) ++counts[e];
    json elements = json::array();
    for (std::size_t i = 0; i < p.options.palette.elements.size(); ++i) {
      json e = element_json(p.options.palette.elements[i], i);
      e["voxels"] = counts[i];
      elements.push_back(std::move(e));
    }
    json body = {{"job", job.id},
                 {"palette", p.palette_name},
                 {"metric", to_string(p.options.metric)},
                 {"rays", p.options.rays},
                 {"points", p.options.points},
                 {"seed", p.options.seed},
                 {"voxel_aspect", {p.voxel_aspect.x, p.voxel_aspect.y, p.voxel_aspect.z}},
                 {"element_coordinates", "voxel coordinates [0, 1]^3; a half-space [nx, ny, nz, d] holds nx x + ny y + nz z <= d; "
                                         "an element is the union of its pieces, a piece the intersection of its half-spaces"},
                 {"similarity", "the volume's layer=similarity holds round(255 B), B the share of the voxel's sample points "
                                "where the element and the part agree; 0 also when no element was admissible"},
                 {"elements", std::move(elements)}};
    if (!p.render.empty()) {
      auto similarity = jobs.similarity(job.id);
      if (!similarity) throw unknown_job(job.id);
      const DenseVolume<std::uint8_t> shown = render_palette(element, *similarity, p.render);
      std::vector<std::uint64_t> display(p.render.objects.size() + 1, 0);
      for (std::uint8_t o : shown.values()) ++display[o];
      json objects = json::array();
      for (std::size_t i = 0; i < p.render.objects.size(); ++i)
        objects.push_back({{"index", i + 1}, {"name", p.render.objects[i]}, {"voxels", display[i + 1]}});
      json rules = json::object();
      for (std::size_t e = 0; e < p.render.by_element.size(); ++e) {
        if (p.render.by_element[e].empty()) continue;
        json list = json::array();
        for (const DisplayChoice& c : p.render.by_element[e])
          list.push_back({{"object", p.render.objects[c.object - 1u]}, {"min_similarity", c.min_similarity}});
        rules[p.options.palette.elements[e].name] = std::move(list);
      }
      body["render"] = {{"objects", std::move(objects)}, {"rules", std::move(rules)}, {"nothing_shown", display[0]}};
    }
    res.set_content(body.dump(2), "application/json");
  }));

  const std::string layer_path = job_path + "/layers/(\\d{1,9})";
  server.Get(layer_path, guarded([&jobs](const Request& req, Response& res) {
    const JobSnapshot job = succeeded_job(jobs, req.matches[1]);
    auto values = jobs.values(job.id);
    if (!values || !std::holds_alternative<DenseVolume<Rgba8>>(*values)) throw wrong_mode(job, "PNG layers", "slice");
    const auto& colours = std::get<DenseVolume<Rgba8>>(*values);
    const std::int64_t k = std::stoll(req.matches[2]);
    if (k >= colours.grid().dims.z)
      throw ProblemError(make_problem(404, "not-found", "No such layer",
                                      "layer " + std::to_string(k) + " is outside 0.." + std::to_string(colours.grid().dims.z - 1) +
                                          " (the grid's z layers)"));
    VectorSink out;
    write_png_layer(colours, k, out);
    res.set_content(std::string(out.data.begin(), out.data.end()), "image/png");
  }));
  return {palette_path, layer_path};
}

}  // namespace voxd::server
