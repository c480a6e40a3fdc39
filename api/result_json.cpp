#include "api/result_json.h"

namespace voxd::api {
namespace {

nlohmann::json vec(const glm::dvec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

}  // namespace

nlohmann::json to_json(const MeshReport& r) {
  nlohmann::json out = {
      {"triangles", r.triangles},
      {"vertices", r.vertices},
      {"bbox_min", vec(r.bbox.min)},
      {"bbox_max", vec(r.bbox.max)},
      {"degenerate_triangles", r.degenerate_triangles},
      {"boundary_edges", r.boundary_edges},
      {"nonmanifold_edges", r.nonmanifold_edges},
      {"inconsistent_edges", r.inconsistent_edges},
      {"watertight", r.watertight},
      {"surface_area", r.surface_area},
      // A signed volume of an open mesh means nothing; say so with null.
      {"volume", r.watertight ? nlohmann::json(r.volume) : nlohmann::json(nullptr)},
  };
  if (!r.warnings.empty()) out["warnings"] = r.warnings;
  if (r.orientation) out["orientation"] = to_json(*r.orientation);
  return out;
}

nlohmann::json to_json(const OrientationRepair& r) {
  return {
      {"components", r.components},
      {"inconsistent_edges", r.inconsistent_edges},
      {"flipped_triangles", r.flipped_triangles},
      {"inconsistent_triangles", r.inconsistent_triangles},
      {"inverted_components", r.inverted_components},
      {"unorientable_edges", r.unorientable_edges},
  };
}

nlohmann::json to_json(const Grid& g) {
  return {
      {"origin", vec(g.origin)},
      {"voxel_size", g.voxel_size},
      {"dims", nlohmann::json::array({g.dims.x, g.dims.y, g.dims.z})},
      {"voxel_count", g.voxel_count()},
  };
}

std::string volume_content(const nlohmann::json& values) {
  if (values.is_null()) return "voxels (1 = filled)";
  std::string text = values.value("quantity", "values");
  if (values.contains("unit")) text += " (" + values.at("unit").get<std::string>();
  if (values.contains("sign_convention")) text += ", " + values.at("sign_convention").get<std::string>();
  if (values.contains("unit")) text += ")";
  return text;
}

}  // namespace voxd::api
