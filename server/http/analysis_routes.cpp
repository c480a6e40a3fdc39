#include "server/http/analysis_routes.h"

#include <charconv>
#include <cmath>
#include <string>
#include <vector>

#include <httplib.h>

#include "api/analysis_json.h"
#include "server/http/problem.h"
#include "server/jobs/job_manager.h"
#include "voxd/analysis.h"
#include "voxd/analysis_images.h"
#include "voxd/error.h"
#include "voxd/radiography.h"
#include "voxd/section.h"

namespace voxd::server {
namespace {

using httplib::Request;
using httplib::Response;
using nlohmann::json;

ProblemError invalid_query(const std::string& detail) {
  return ProblemError(make_problem(400, "invalid-query", "Invalid query parameter", detail));
}

// A query value from a fixed list; `fallback` when absent.
std::string choice(const Request& req, const char* name, std::initializer_list<const char*> allowed, const char* fallback) {
  if (!req.has_param(name)) return fallback;
  const std::string v = req.get_param_value(name);
  std::string list;
  for (const char* a : allowed) {
    if (v == a) return v;
    list += list.empty() ? a : std::string(", ") + a;
  }
  throw invalid_query(std::string(name) + " must be one of " + list + ", got '" + v + "'");
}

int axis_of(const Request& req) {
  const std::string a = choice(req, "axis", {"x", "y", "z"}, "z");
  return a[0] - 'x';
}

std::optional<double> number(const Request& req, const char* name) {
  if (!req.has_param(name)) return std::nullopt;
  const std::string v = req.get_param_value(name);
  double x = 0;
  const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), x);
  if (ec != std::errc() || end != v.data() + v.size() || !std::isfinite(x))
    throw invalid_query(std::string(name) + " must be a number, got '" + v + "'");
  return x;
}

std::string number_key(double x) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, x);
  (void)ec;
  return std::string(buf, end);
}

struct FinishedJob {
  JobSnapshot snapshot;
  std::shared_ptr<const BitVolume> volume;
};

FinishedJob finished_job(JobManager& jobs, const std::string& id) {
  auto unknown = [&] {
    return ProblemError(make_problem(404, "not-found", "Unknown job", "no job with id " + id + " (it may have expired or been deleted)"));
  };
  const auto job = jobs.get(id);
  if (!job) throw unknown();
  if (job->state != JobState::succeeded)
    throw ProblemError(make_problem(409, "job-not-finished", "The job has no volume yet",
                                    std::string("the job is ") + to_string(job->state) + "; its analyses exist once it has succeeded"));
  auto volume = jobs.volume(id);
  if (!volume) throw unknown();
  return {*job, std::move(volume)};
}

// Answers from the job's kept artifact, or computes, keeps and answers it.
void answer_artifact(JobManager& jobs, const std::string& id, const std::string& key, const char* content_type, Response& res,
                     const std::function<std::string()>& compute) {
  if (auto kept = jobs.load_artifact(id, key)) {
    res.set_header("X-Voxd-Cache", "hit");
    res.set_content(*kept, content_type);
    return;
  }
  std::string bytes = compute();
  jobs.save_artifact(id, key, bytes);
  res.set_header("X-Voxd-Cache", "miss");
  res.set_content(std::move(bytes), content_type);
}

std::string scale_header(double per_value, const std::string& unit) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", per_value);
  return std::string("1 pixel value = ") + buf + " " + unit;
}

}  // namespace

std::vector<std::string> install_analysis_routes(httplib::Server& server, JobManager& jobs, const std::string& job_path,
                                                 const Guard& guarded) {
  const std::string analysis = job_path + "/analysis", radiography_path = job_path + "/radiography",
                    section_path = job_path + "/section";

  server.Get(analysis, guarded([&jobs](const Request& req, Response& res) {
    const std::string id = req.matches[1];
    const std::string cleanup = choice(req, "cleanup", {"none", "debris", "sheets"}, "none");
    const std::string thickness = choice(req, "thickness", {"true", "false"}, "true");
    const auto min_wall = number(req, "min_wall"), max_wall = number(req, "max_wall");
    if ((min_wall && *min_wall <= 0) || (max_wall && *max_wall <= 0))
      throw invalid_query("min_wall and max_wall are positive lengths in model units");
    if ((min_wall || max_wall) && thickness == "false")
      throw invalid_query("min_wall and max_wall need the thickness analysis; drop thickness=false");
    const FinishedJob job = finished_job(jobs, id);
    const std::string key = "analysis-" + cleanup + "-" + thickness + "-" + number_key(min_wall.value_or(0)) + "-" +
                            number_key(max_wall.value_or(0)) + ".json";
    answer_artifact(jobs, id, key, "application/json", res, [&] {
      AnalysisOptions options;
      if (cleanup != "none") options.cleanup = CleanupOptions{true, true, cleanup == "sheets"};
      options.thickness = thickness == "true";
      options.min_wall_voxels = min_wall.value_or(0) / job.snapshot.grid.voxel_size;
      options.max_wall_voxels = max_wall.value_or(0) / job.snapshot.grid.voxel_size;
      const AnalysisReport report = analyze_volume(*job.volume, options);
      return api::analysis_to_json(report, job.snapshot.grid, job.snapshot.mesh, job.snapshot.mesh_mass).dump();
    });
  }));

  server.Get(radiography_path, guarded([&jobs](const Request& req, Response& res) {
    const std::string id = req.matches[1];
    const int axis = axis_of(req);
    const std::string measure = choice(req, "measure", {"min", "max", "total"}, "max");
    const std::string format = choice(req, "format", {"png16", "png", "json"}, "png16");
    const std::string unit = choice(req, "unit", {"voxels", "model"}, "voxels");
    const FinishedJob job = finished_job(jobs, id);
    const double h = job.snapshot.grid.voxel_size;
    // Pixel values are voxel counts; the scale says what one is worth.
    const PngScale scale = unit == "model" ? PngScale{h, "model units"} : PngScale{1.0, "voxel"};
    res.set_header("X-Voxd-Scale", scale_header(scale.per_value, scale.unit));
    const std::string key = std::string("radiography-") + "xyz"[axis] + "-" + measure + "-" + format + "-" + unit;
    answer_artifact(jobs, id, key, format == "json" ? "application/json" : "image/png", res, [&] {
      const ThicknessImage image = radiography(*job.volume, axis);
      const RadiographyMeasure m = measure == "min" ? RadiographyMeasure::min
                                   : measure == "max" ? RadiographyMeasure::max
                                                      : RadiographyMeasure::total;
      if (format == "json") {
        const ThicknessStats s = thickness_stats(values_of(image, m), 32);
        json histogram = json::array();
        for (std::uint64_t n : s.histogram) histogram.push_back(n);
        const double k = scale.per_value;
        return json{{"axis", std::string(1, "xyz"[axis])}, {"measure", measure}, {"unit", scale.unit},
                    {"voxel_size", h}, {"width", image.width}, {"height", image.height}, {"rays", s.rays},
                    {"min", s.min * k}, {"max", s.max * k}, {"mean", s.mean * k},
                    {"p5", s.p5 * k}, {"p50", s.p50 * k}, {"p95", s.p95 * k},
                    {"histogram", {{"min", s.min * k}, {"bin_width", s.bin_width * k}, {"counts", histogram}}}}
            .dump();
      }
      const auto png = radiography_png(image, axis, m, format == "png", scale, {{"voxd:job", id}});
      return std::string(png.begin(), png.end());
    });
  }));

  server.Get(section_path, guarded([&jobs](const Request& req, Response& res) {
    const std::string id = req.matches[1];
    const int axis = axis_of(req);
    const auto index_param = number(req, "index");
    const auto coordinate = number(req, "coordinate");
    if (index_param.has_value() == coordinate.has_value())
      throw invalid_query("give exactly one of index (voxel layer) or coordinate (model units)");
    const FinishedJob job = finished_job(jobs, id);
    const Grid& g = job.snapshot.grid;
    std::int64_t index = 0;
    try {
      index = coordinate ? section_index(g, axis, *coordinate) : static_cast<std::int64_t>(*index_param);
    } catch (const Error& e) {
      throw invalid_query(e.what());
    }
    if (index_param && (*index_param != std::floor(*index_param) || index < 0 || index >= g.dims[axis]))
      throw invalid_query("index must be an integer from 0 to " + std::to_string(g.dims[axis] - 1) + " along " +
                          std::string(1, "xyz"[axis]));
    const std::string key = std::string("section-") + "xyz"[axis] + "-" + std::to_string(index) + ".png";
    answer_artifact(jobs, id, key, "image/png", res, [&] {
      const auto png = section_png(*job.volume, axis, index, {{"voxd:job", id}});
      return std::string(png.begin(), png.end());
    });
  }));
  return {analysis, radiography_path, section_path};
}

}  // namespace voxd::server
