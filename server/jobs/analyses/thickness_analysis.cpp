// The thickness volume: the wall or local thickness of every voxel of the
// solid, in model units or voxels, as NRRD, raw floats or RLE; or the same
// on the part's own mesh (the job's kept mesh, kept_mesh.h), each vertex
// taking the wall under it, as PLY, glb or JSON.
#include "server/jobs/analyses/analysis_support.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "server/jobs/kept_mesh.h"
#include "voxd/analysis/surface_thickness.h"
#include "voxd/analysis/wall_thickness.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/thickness_mesh.h"
#include "voxd/encode/volume_format.h"
#include "voxd/transform.h"

namespace voxd::server {
namespace {

// The thickness map in the unit asked for: voxels as computed, or model
// units (times the voxel size).
DenseVolume<float> thickness_in(DenseVolume<float> map, const std::string& unit) {
  if (unit == "model") {
    const auto h = static_cast<float>(map.grid().voxel_size);
    for (float& v : map.values()) v *= h;
  }
  return map;
}

bool on_mesh(const api::AnalysisRequest& r) { return r.format == "ply" || r.format == "glb" || r.format == "json"; }

// The thickness on the job's kept mesh, in the request's format.
std::string on_part(const AnalysisInput& in, const DenseVolume<float>& map) {
  const api::AnalysisRequest& r = in.request;
  const auto kept = in.artifacts.load(kKeptMeshKey);
  if (!kept)
    throw AnalysisRejected("this job kept no mesh to show its thickness on (it ran before the service kept its jobs' "
                           "meshes): submit it again, or ask for format=nrrd, raw or rle");
  const KeptMesh k = decode_kept_mesh(*kept);
  // Read in the grid's frame: turned exactly as the job turned it.
  Mesh in_grid = k.mesh;
  rotate_mesh(in_grid, k.rotation);
  const double h = map.grid().voxel_size;
  std::optional<float> thin_below;
  if (r.min_wall) thin_below = static_cast<float>(*r.min_wall / h - kWallReportTolerance);
  SurfaceThickness s = surface_thickness(in_grid, map, thin_below);
  const double scale = r.unit == "model" ? h : 1.0;
  for (float& t : s.thickness) t = static_cast<float>(t * scale);

  // Over the surface: each vertex stands for a third of its triangles' area.
  std::vector<double> area(k.mesh.vertices.size(), 0.0);
  for (const auto& t : k.mesh.triangles) {
    const glm::dvec3 a(k.mesh.vertices[t[0]]), b(k.mesh.vertices[t[1]]), c(k.mesh.vertices[t[2]]);
    const double third = glm::length(glm::cross(b - a, c - a)) / 6.0;
    for (const std::uint32_t v : t) area[v] += third;
  }
  double lo = std::numeric_limits<double>::infinity(), hi = 0, sum = 0, weight = 0;
  for (std::size_t i = 0; i < s.thickness.size(); ++i) {
    if (!(s.thickness[i] > 0)) continue;
    lo = std::min<double>(lo, s.thickness[i]);
    hi = std::max<double>(hi, s.thickness[i]);
    sum += area[i] * s.thickness[i];
    weight += area[i];
  }
  const bool any = weight > 0 || hi > 0;
  ThicknessColours colours;
  colours.low = static_cast<float>(r.min_wall ? *r.min_wall / h * scale : (any ? lo : 0.0));
  colours.high = static_cast<float>(r.max_wall ? *r.max_wall / h * scale : (any ? hi : 1.0));
  const std::string unit = r.unit == "model" ? "model units" : "voxels";
  VectorSink out;
  if (r.format == "ply") {
    write_thickness_ply(k.mesh, s.thickness, colours, unit, out);
    return to_bytes(out.data);
  }
  if (r.format == "glb") {
    write_thickness_glb(k.mesh, s.thickness, colours, unit, out);
    return to_bytes(out.data);
  }
  using nlohmann::json;
  const Grid& g = map.grid();
  const glm::dmat3 back = glm::transpose(k.rotation);  // the grid's frame -> the mesh's
  std::vector<std::uint64_t> vertices_in(s.thin_regions.size(), 0);
  for (const std::uint32_t id : s.thin_region)
    if (id > 0) ++vertices_in[id - 1];
  json regions = json::array();
  for (std::size_t i = 0; i < s.thin_regions.size(); ++i) {
    const ThicknessRegion& t = s.thin_regions[i];
    const glm::dvec3 c = back * (g.origin + (t.centroid + glm::dvec3(0.5)) * h);
    regions.push_back({{"id", i + 1},
                       {"voxels", t.voxel_count},
                       {"volume", static_cast<double>(t.voxel_count) * h * h * h},
                       {"centroid", {c.x, c.y, c.z}},
                       {"min_thickness", t.extreme_thickness * scale},
                       {"mean_thickness", t.mean_thickness * scale},
                       {"vertices", vertices_in[i]}});
  }
  json j = {{"measure", to_string(r.thickness_measure)},
            {"unit", r.unit},
            {"vertices", k.mesh.vertices.size()},
            {"triangles", k.mesh.triangles.size()},
            {"min", any ? json(lo) : json(nullptr)},
            {"max", any ? json(hi) : json(nullptr)},
            {"mean", weight > 0 ? json(sum / weight) : json(nullptr)},
            {"min_wall", r.min_wall ? json(*r.min_wall) : json(nullptr)},
            {"max_wall", r.max_wall ? json(*r.max_wall) : json(nullptr)},
            {"unresolved", s.unresolved},
            {"thickness", s.thickness},
            {"thin_region", r.min_wall ? json(s.thin_region) : json(std::vector<std::uint32_t>(s.thickness.size(), 0))},
            {"thin_regions", regions}};
  return j.dump();
}

class ThicknessAnalysis final : public JobAnalysisKind {
 public:
  api::AnalysisKind kind() const override { return api::AnalysisKind::thickness; }

  std::string compute(const AnalysisInput& in, const BitVolume& volume) const override {
    const api::AnalysisRequest& r = in.request;
    if (on_mesh(r)) return on_part(in, *job_thickness_map(volume, in.artifacts, in.control, r.thickness_measure));
    const auto map = job_thickness_map(volume, in.artifacts, in.control, r.thickness_measure);
    StringSink out;
    if (r.format == "rle") {
      write_rle(thickness_in(*map, r.unit), out);
      return std::move(out.data);
    }
    // NRRD and raw are the floats (and a header), scaled as they are
    // written: the map is neither copied nor its bytes gathered twice.
    out.data.reserve(map->values().size() * sizeof(float) + 4096);
    const float scale = r.unit == "model" ? static_cast<float>(map->grid().voxel_size) : 1.0f;
    if (r.format == "raw") {
      write_raw(*map, out, scale);
    } else {
      write_nrrd(*map,
                 std::string(to_string(r.thickness_measure)) + " thickness (" +
                     (r.unit == "model" ? "model units" : "voxels") + ")",
                 out, NrrdEncoding::raw, scale);
    }
    return std::move(out.data);
  }

  // The map's 18 bytes a voxel, then the map in the asked unit (RLE only),
  // the encoded volume and its kept copy.
  std::uint64_t whole_grid_bytes_per_voxel(const api::AnalysisRequest&) const override { return 18 + 12; }

  // On the part: the kept mesh read, decoded and turned (18 bytes a
  // triangle each, a welded mesh having about half a vertex a triangle),
  // its normals, values and areas (about 40), and the file made, copied out
  // and kept (about 40 each for glb, a little more for JSON's text): 256.
  std::uint64_t bytes_per_triangle(const api::AnalysisRequest& r) const override { return on_mesh(r) ? 256 : 0; }

  std::string needs_whole_grid(const api::AnalysisRequest& r) const override {
    return std::string("the ") + to_string(r.thickness_measure) + " thickness volume";
  }
};

}  // namespace

const JobAnalysisKind& thickness_analysis() {
  static const ThicknessAnalysis kind;
  return kind;
}

}  // namespace voxd::server
