#include "api/job_warning.h"

#include <algorithm>
#include <cstdio>


namespace voxd::api {
namespace {

using nlohmann::json;

std::string mm(double v, const char* unit = "mm") {
  char text[48];
  std::snprintf(text, sizeof text, "%.4g %s", v, unit);
  return text;
}

// The unit that would bring a part `size` millimetres across into 1 mm to
// 10 m, if one does.
std::optional<LengthUnit> likely_unit(double size, LengthUnit given) {
  const double raw = size / millimetres_per(given);  // the file's numbers
  for (LengthUnit u : {LengthUnit::m, LengthUnit::in, LengthUnit::cm, LengthUnit::mm}) {
    const double across = raw * millimetres_per(u);
    if (u != given && across >= 1.0 && across <= 10000.0) return u;
  }
  return std::nullopt;
}

}  // namespace

json to_json(const std::vector<JobWarning>& warnings) {
  json out = json::array();
  for (const JobWarning& w : warnings) out.push_back({{"code", w.code}, {"message", w.message}, {"details", w.details}});
  return out;
}

std::vector<JobWarning> warnings_from_json(const json& list) {
  std::vector<JobWarning> out;
  if (!list.is_array()) return out;
  for (const json& w : list) out.push_back({w.at("code"), w.at("message"), w.value("details", json::object())});
  return out;
}

std::optional<JobWarning> leaky_inside_warning(const InsideChoice& inside, std::uint64_t boundary_edges,
                                               std::uint64_t nonmanifold_edges) {
  if (inside.automatic || inside.test == InsideTest::winding || (boundary_edges == 0 && nonmanifold_edges == 0))
    return std::nullopt;
  JobWarning w;
  w.code = "open-mesh-parity";
  w.message = "the mesh is not closed (" + std::to_string(boundary_edges) + " boundary, " +
              std::to_string(nonmanifold_edges) + " non-manifold edges) and the " + to_string(inside.test) +
              " inside test counts crossings, which fill streaks through its holes out to the grid's border";
  w.message += inside.reason.empty() ? "; use \"inside\": \"auto\" or \"winding\"" : " (" + inside.reason + ")";
  w.details = {{"inside", to_string(inside.test)}, {"boundary_edges", boundary_edges}, {"nonmanifold_edges", nonmanifold_edges}};
  return w;
}

std::vector<JobWarning> prepared_job_warnings(const JobParams& params, const InsideChoice& inside,
                                              const OrientationRepair* repair, const Aabb& box, const Grid& grid) {
  std::vector<JobWarning> out;
  if (repair) {
    if (auto w = leaky_inside_warning(inside, repair->boundary_edges, repair->nonmanifold_edges)) out.push_back(*w);
    if (repair->inverted_components > 0)
      out.push_back({"mesh-inverted",
                     std::to_string(repair->inverted_components) + " of the mesh's " + std::to_string(repair->components) +
                         " connected parts were inside out (their normals pointed into the solid) and were turned round",
                     {{"inverted_components", repair->inverted_components}, {"components", repair->components}}});
    if (repair->inconsistent_triangles > 0)
      out.push_back({"mesh-reoriented",
                     std::to_string(repair->inconsistent_triangles) +
                         " triangles faced the other way from their neighbours and were turned to agree",
                     {{"inconsistent_triangles", repair->inconsistent_triangles},
                      {"inconsistent_edges", repair->inconsistent_edges}}});
    if (repair->unorientable_edges > 0)
      out.push_back({"mesh-unorientable",
                     std::to_string(repair->unorientable_edges) +
                         " edges join triangles that no orientation makes agree (a surface folded through itself or a "
                         "Moebius strip): the winding number is unreliable near them",
                     {{"unorientable_edges", repair->unorientable_edges}}});
  }
  const glm::dvec3 extent = box.extent();
  const double size = std::max({extent.x, extent.y, extent.z});
  if (size > 0.0 && (size < 1.0 || size > 10000.0)) {
    JobWarning w{"implausible-size",
                 "the part is " + mm(size) + " across in " + to_string(params.units) + " (\"units\": \"" +
                     to_string(params.units) + "\"), " + (size < 1.0 ? "under 1 mm" : "over 10 m"),
                 {{"size_mm", size}, {"units", to_string(params.units)}}};
    if (const auto u = likely_unit(size, params.units)) {
      w.message += std::string("; if this mesh is in ") + (*u == LengthUnit::m ? "metres" : to_string(*u)) +
                   ", set \"units\": \"" + to_string(*u) + "\"";
      w.details["likely_units"] = to_string(*u);
    }
    out.push_back(std::move(w));
  }
  if (size > 0.0 && grid.voxel_size > size)
    out.push_back({"voxel-larger-than-part",
                   "the voxel (" + mm(grid.voxel_size) + ") is larger than the part (" + mm(size) +
                       " across): the result cannot show its shape; use a smaller voxel_size or a resolution",
                   {{"voxel_size", grid.voxel_size}, {"size_mm", size}}});
  for (const AnalysisRequest& a : params.analyses)
    for (const auto& [name, value] : {std::pair{"min_wall", a.min_wall}, std::pair{"max_wall", a.max_wall}})
      if (value && size > 0.0 && *value > size)
        out.push_back({"wall-limit-exceeds-part",
                       std::string(name) + " (" + mm(*value) + ") is larger than the part (" + mm(size) +
                           " across): every wall reads below it; check \"units\"",
                       {{"parameter", name}, {"value", *value}, {"size_mm", size}}});
  return out;
}

std::optional<JobWarning> empty_result_warning(const JobParams& params, const InsideChoice& inside,
                                               std::uint64_t filled, double surface_area) {
  if (filled > 0 || !(surface_area > 0.0) || params.mode->voxel_mode() == VoxelMode::surface) return std::nullopt;
  JobWarning w{"empty-result",
               "nothing was filled although the mesh has " + mm(surface_area, "mm²") +
                   " of surface: it encloses no voxel centre (a sheet, a thin or open surface, or a part smaller than a voxel)",
               {{"surface_area", surface_area}, {"inside", to_string(inside.test)}}};
  w.message += inside.test == InsideTest::winding ? "; try \"mode\": \"surface\", or a smaller voxel"
                                                  : "; try \"mode\": \"surface\", \"inside\": \"winding\", or a smaller voxel";
  return w;
}

}  // namespace voxd::api
