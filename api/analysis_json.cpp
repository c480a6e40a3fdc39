#include "api/analysis_json.h"

#include <cmath>

#include <glm/geometric.hpp>

#include "voxd/encode/number_text.h"

namespace voxd::api {
namespace {

using nlohmann::json;

json vec(glm::dvec3 v) { return json::array({v.x, v.y, v.z}); }

json region_json(const VoxelRegion& r, const Grid& g) {
  const double h = g.voxel_size;
  return {{"voxels", r.voxels},
          {"volume", static_cast<double>(r.voxels) * h * h * h},
          {"centroid", vec(region_centroid_model(r, g))},
          {"bbox_min", vec(g.origin + glm::dvec3(r.bbox_min) * h)},
          {"bbox_max", vec(g.origin + glm::dvec3(r.bbox_max + glm::i64vec3(1)) * h)}};
}

json regions_json(const std::vector<VoxelRegion>& regions, const Grid& g) {
  json items = json::array();
  std::uint64_t voxels = 0;
  for (std::size_t i = 0; i < regions.size(); ++i) {
    voxels += regions[i].voxels;
    if (i < kMaxListedRegions) items.push_back(region_json(regions[i], g));
  }
  const double h = g.voxel_size;
  return {{"count", regions.size()}, {"total_voxels", voxels}, {"total_volume", static_cast<double>(voxels) * h * h * h},
          {"items", items}};
}

double relative(double voxel, double exact) { return exact != 0 ? (voxel - exact) / std::abs(exact) : 0.0; }

}  // namespace

json to_json(const MassProperties& p) {
  json inertia = json::array();
  for (int r = 0; r < 3; ++r) inertia.push_back(json::array({p.inertia[0][r], p.inertia[1][r], p.inertia[2][r]}));
  return {{"volume", p.volume}, {"centroid", vec(p.centroid)}, {"inertia", inertia},
          {"bbox_min", vec(p.bbox.min)}, {"bbox_max", vec(p.bbox.max)}};
}

json analysis_to_json(const AnalysisReport& report, const Grid& grid, const std::optional<MeshReport>& mesh,
                      const std::optional<MassProperties>& mesh_mass) {
  const double h = grid.voxel_size;
  json mass = {{"voxels", to_json(report.voxels)}};
  if (mesh && mesh->watertight && mesh_mass) {
    json m = to_json(*mesh_mass);
    m["available"] = true;
    m["surface_area"] = mesh->surface_area;
    mass["mesh"] = m;
    // How far the voxel model is from the exact part: the volume, the centroid
    // (as a fraction of the voxel size) and the inertia tensor (relative,
    // Frobenius norm).
    double diff = 0, norm = 0;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        diff += std::pow(report.voxels.inertia[a][b] - mesh_mass->inertia[a][b], 2);
        norm += std::pow(mesh_mass->inertia[a][b], 2);
      }
    mass["difference"] = {{"volume_relative", relative(report.voxels.volume, mesh_mass->volume)},
                          {"centroid_voxels", glm::length(report.voxels.centroid - mesh_mass->centroid) / h},
                          {"inertia_relative", norm > 0 ? std::sqrt(diff / norm) : 0.0}};
  } else {
    std::string reason = "no mesh report for this job";
    if (mesh)
      reason = "the mesh is not closed (" + std::to_string(mesh->boundary_edges) + " boundary edges, " +
               std::to_string(mesh->nonmanifold_edges) +
               " non-manifold edges): its exact volume, centroid and inertia are undefined; the voxel values describe the "
               "voxelized solid";
    mass["mesh"] = {{"available", false}, {"reason", reason}};
    mass["difference"] = nullptr;
  }
  json skin = nullptr;
  if (report.skin) {
    json layers = json::array();
    for (std::uint64_t n : report.skin->voxels_per_layer) layers.push_back(n);
    json hot_spots = json::array();
    for (std::size_t i = 0; i < report.skin->innermost.size() && i < kMaxListedRegions; ++i)
      hot_spots.push_back(region_json(report.skin->innermost[i], grid));
    skin = {{"metric", to_string(report.peel)},
            {"connectivity", report.peel == PeelMetric::faces ? json(6) : json(nullptr)},
            {"layers", layers},
            {"max_depth_layers", report.skin->max_depth},
            {"max_depth", static_cast<double>(report.skin->max_depth) * h},
            {"hot_spots", hot_spots}};
  }
  json thickness = nullptr;
  if (report.thickness) {
    const ThicknessAnalysis& t = *report.thickness;
    // `kind` set: each region says whether it is certainly beyond the
    // threshold (else it is marginal); unset: regions near the threshold.
    auto regions = [&](const std::vector<ThicknessRegion>& list, const char* extreme,
                       std::optional<ThicknessRegionKind> kind = std::nullopt) {
      json items = json::array();
      std::size_t marginal = 0;
      for (const ThicknessRegion& r : list)
        if (!kind || !certainly_beyond(t, r, *kind)) ++marginal;
      for (std::size_t i = 0; i < list.size() && i < kMaxListedRegions; ++i) {
        const ThicknessRegion& r = list[i];
        items.push_back({{"voxels", r.voxel_count},
                         {"certain", kind ? json(certainly_beyond(t, r, *kind)) : json(false)},
                         {"volume", static_cast<double>(r.voxel_count) * h * h * h},
                         {"centroid", vec(grid.origin + (r.centroid + glm::dvec3(0.5)) * h)},
                         {"bbox_min", vec(grid.origin + glm::dvec3(r.bbox_min) * h)},
                         {"bbox_max", vec(grid.origin + glm::dvec3(r.bbox_max + glm::i64vec3(1)) * h)},
                         {extreme, static_cast<double>(r.extreme_thickness) * h},
                         {"mean_thickness", static_cast<double>(r.mean_thickness) * h}});
      }
      return json{{"count", list.size()}, {"marginal", marginal}, {"items", items}};
    };
    const ThicknessVerdict verdict = thickness_verdict(t);
    const std::optional<double> deciding = deciding_voxel_size(t);
    json verdict_json = nullptr, reason = nullptr;
    const ThicknessErrorBound b = wall_thickness_error_bound();
    const std::string bound = "the error bound (-" + number_text(b.below_voxels) + " to +" + number_text(b.above_voxels) +
                              " voxel, -" + number_text(b.below_voxels * h) + " to +" + number_text(b.above_voxels * h) +
                              " mm)";
    switch (verdict) {
      case ThicknessVerdict::none: break;
      case ThicknessVerdict::pass:
        verdict_json = "pass";
        reason = "every wall reads within the thresholds by more than " + bound;
        break;
      case ThicknessVerdict::fail:
        verdict_json = "fail";
        reason = "a region reads beyond a threshold by more than " + bound + ": the wall itself is beyond it";
        break;
      case ThicknessVerdict::inconclusive:
        verdict_json = "inconclusive";
        reason = "no region is certainly beyond a threshold, but some read within " + bound +
                 " of one, so the walls there may be on either side; voxels of " + number_text(*deciding * h) + " mm" +
                 " or smaller would decide it (voxel_size_to_decide)";
        break;
    }
    json histogram = json::array();
    for (std::uint64_t n : t.stats.histogram) histogram.push_back(n);
    thickness = {
        {"measure", "wall"},
        {"method", "wall thickness: the distance between the wall's two faces, from a theta-medial axis (Foskey, Lin & "
                   "Manocha 2003; faces at least 150 degrees apart); each voxel takes the wall's section through its "
                   "nearest medial point, so edges and corners take the wall they end"},
        {"error_bound", wall_thickness_error_statement(h)},
        {"reading_bound",
         {{"below", b.below_voxels * h}, {"above", b.above_voxels * h}, {"tolerance", kWallReportTolerance * h}}},
        {"voxels", t.stats.voxel_count},
        {"mean", t.stats.mean * h},
        {"std", t.stats.std_dev * h},
        {"min", t.stats.min * h},
        {"max", t.stats.max * h},
        {"histogram", {{"min", t.stats.min * h}, {"bin_width", t.stats.bin_width() * h}, {"counts", histogram}}},
        {"min_wall", t.min_wall_voxels > 0 ? json(t.min_wall_voxels * h) : json(nullptr)},
        {"max_wall", t.max_wall_voxels > 0 ? json(t.max_wall_voxels * h) : json(nullptr)},
        {"thin_regions", regions(t.thin_regions, "min_thickness", ThicknessRegionKind::thin)},
        {"thick_regions", regions(t.thick_regions, "max_thickness", ThicknessRegionKind::thick)},
        {"near_min_wall", regions(t.near_min_wall, "min_thickness")},
        {"near_max_wall", regions(t.near_max_wall, "max_thickness")},
        {"verdict", verdict_json},
        {"verdict_reason", reason},
        {"voxel_size_to_decide", deciding ? json(*deciding * h) : json(nullptr)},
    };
  }
  json out = {
      {"unit", "mm"},
      {"voxel_size", h},
      {"grid", {{"origin", vec(grid.origin)}, {"dims", json::array({grid.dims.x, grid.dims.y, grid.dims.z})}}},
      {"mass_properties", mass},
      {"parts", regions_json(report.components.parts, grid)},
      {"voids", regions_json(report.components.voids, grid)},
      {"skin", skin},
      {"thickness", thickness},
      {"cleanup", report.cleanup ? json{{"isolated", report.cleanup->isolated},
                                        {"lines", report.cleanup->lines},
                                        {"sheets", report.cleanup->sheets}}
                                 : json(nullptr)},
  };
  return out;
}

}  // namespace voxd::api
