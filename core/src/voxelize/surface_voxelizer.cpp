// Conservative surface voxelization: every voxel whose closed cube the
// triangle touches. The test is the separating-axis test in the form of
// Schwarz & Seidel 2010 (plane overlap + the three 2D edge-function tests),
// evaluated per column of the triangle's dominant projection so the cost is
// proportional to the voxels produced, not to the triangle's bounding box.
#include <algorithm>
#include <atomic>
#include <cmath>

#include <glm/geometric.hpp>

#include "voxd/parallel.h"
#include "voxd/voxelize/voxelize.h"
#include "voxelize/surface_voxelizer.h"

namespace voxd {
namespace {

// 2D edge tests of the triangle projected on one coordinate plane (c0, c1),
// with the unit square at `p` (its minimum corner).
struct ProjectedEdges {
  int c0 = 0, c1 = 1;
  double nx[3]{}, ny[3]{}, d[3]{};

  void init(const glm::dvec3 v[3], int a0, int a1, double normal_sign) {
    c0 = a0;
    c1 = a1;
    for (int e = 0; e < 3; ++e) {
      const glm::dvec3 edge = v[(e + 1) % 3] - v[e];
      nx[e] = -edge[c1] * normal_sign;
      ny[e] = edge[c0] * normal_sign;
      d[e] = -(nx[e] * v[e][c0] + ny[e] * v[e][c1]) + std::max(0.0, nx[e]) + std::max(0.0, ny[e]);
    }
  }
  bool overlaps(double p0, double p1) const {
    for (int e = 0; e < 3; ++e)
      if (nx[e] * p0 + ny[e] * p1 + d[e] < 0.0) return false;
    return true;
  }
};

// Calls emit(i, j, k) for each voxel of z layers [z0, z1) the triangle
// touches; a voxel may come more than once from one triangle's columns only
// if the columns overlap, which they do not.
template <class Emit>
void voxelize_triangle(const glm::dvec3 v[3], const Grid& grid, std::int64_t z0, std::int64_t z1, Emit&& emit) {
  const glm::dvec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
  if (n == glm::dvec3(0.0)) return;  // zero area: covers no surface
  const glm::dvec3 an = glm::abs(n);
  const int d = (an.x >= an.y && an.x >= an.z) ? 0 : (an.y >= an.z ? 1 : 2);
  // Plane pairs (c0, c1) and the normal component that orients each.
  ProjectedEdges planes[3];
  planes[0].init(v, 1, 2, n.x >= 0 ? 1.0 : -1.0);  // yz, seen along x
  planes[1].init(v, 2, 0, n.y >= 0 ? 1.0 : -1.0);  // zx, seen along y
  planes[2].init(v, 0, 1, n.z >= 0 ? 1.0 : -1.0);  // xy, seen along z
  const ProjectedEdges& column_plane = planes[d];
  const ProjectedEdges& other_a = planes[(d + 1) % 3];
  const ProjectedEdges& other_b = planes[(d + 2) % 3];

  glm::dvec3 lo = glm::min(v[0], glm::min(v[1], v[2])), hi = glm::max(v[0], glm::max(v[1], v[2]));
  glm::i64vec3 vlo, vhi;
  for (int a = 0; a < 3; ++a) {
    // Closed cubes: a triangle touching the face at integer t touches cubes t-1 and t.
    vlo[a] = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(lo[a])) - 1);
    vhi[a] = std::min<std::int64_t>(grid.dims[a] - 1, static_cast<std::int64_t>(std::floor(hi[a])));
  }
  vlo.z = std::max(vlo.z, z0);
  vhi.z = std::min(vhi.z, z1 - 1);
  if (vlo.x > vhi.x || vlo.y > vhi.y || vlo.z > vhi.z) return;

  const int a = column_plane.c0, b = column_plane.c1;
  const double plane_offset = glm::dot(n, v[0]);
  for (std::int64_t ia = vlo[a]; ia <= vhi[a]; ++ia) {
    for (std::int64_t ib = vlo[b]; ib <= vhi[b]; ++ib) {
      const double pa = static_cast<double>(ia), pb = static_cast<double>(ib);
      if (!column_plane.overlaps(pa, pb)) continue;
      // Range of the plane's d-coordinate over the column's square.
      double dmin = INFINITY, dmax = -INFINITY;
      for (int corner = 0; corner < 4; ++corner) {
        const double qa = pa + (corner & 1), qb = pb + (corner >> 1);
        const double dv = (plane_offset - n[a] * qa - n[b] * qb) / n[d];
        dmin = std::min(dmin, dv);
        dmax = std::max(dmax, dv);
      }
      const std::int64_t k0 = std::max(vlo[d], static_cast<std::int64_t>(std::ceil(dmin)) - 1);
      const std::int64_t k1 = std::min(vhi[d], static_cast<std::int64_t>(std::floor(dmax)));
      for (std::int64_t kd = k0; kd <= k1; ++kd) {
        glm::i64vec3 idx;
        idx[a] = ia;
        idx[b] = ib;
        idx[d] = kd;
        const glm::dvec3 p(idx);
        if (!other_a.overlaps(p[other_a.c0], p[other_a.c1]) || !other_b.overlaps(p[other_b.c0], p[other_b.c1]))
          continue;
        emit(idx.x, idx.y, idx.z);
      }
    }
  }
}

}  // namespace

namespace detail {

SurfaceVoxelizer::SurfaceVoxelizer(const Mesh& mesh, const Grid& grid, int threads, std::int64_t rows_per_chunk)
    : mesh_(&mesh), grid_(grid), threads_(threads > 0 ? threads : default_thread_count()) {
  // Vertices in voxel units: voxel (i,j,k) is the cube [i,i+1] x [j,j+1] x [k,k+1].
  unit_.resize(mesh.vertices.size());
  for (std::size_t i = 0; i < unit_.size(); ++i) unit_[i] = (glm::dvec3(mesh.vertices[i]) - grid.origin) / grid.voxel_size;

  // Bin triangles by z chunk so each thread writes only its own slabs.
  const std::int64_t nz = grid.dims.z;
  per_chunk_ = rows_per_chunk > 0 ? rows_per_chunk : std::clamp<std::int64_t>(nz / (8 * threads_), 1, 16);
  const std::int64_t chunks = (nz + per_chunk_ - 1) / per_chunk_;
  bins_.resize(static_cast<std::size_t>(chunks));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const double zlo = std::min({unit_[tri[0]].z, unit_[tri[1]].z, unit_[tri[2]].z});
    const double zhi = std::max({unit_[tri[0]].z, unit_[tri[1]].z, unit_[tri[2]].z});
    if (!(zhi >= 0.0) || !(zlo <= static_cast<double>(nz))) continue;
    const std::int64_t k0 = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(zlo)) - 1);
    const std::int64_t k1 = std::min<std::int64_t>(nz - 1, static_cast<std::int64_t>(std::floor(zhi)));
    for (std::int64_t c = k0 / per_chunk_; c <= k1 / per_chunk_; ++c) bins_[static_cast<std::size_t>(c)].push_back(static_cast<std::uint32_t>(t));
  }
}

template <class Emit>
void SurfaceVoxelizer::for_each_voxel(std::int64_t chunk, Emit&& emit) const {
  const std::int64_t z0 = chunk * per_chunk_, z1 = std::min(grid_.dims.z, z0 + per_chunk_);
  for (std::uint32_t t : bins_[static_cast<std::size_t>(chunk)]) {
    const auto& tri = mesh_->triangles[t];
    const glm::dvec3 v[3] = {unit_[tri[0]], unit_[tri[1]], unit_[tri[2]]};
    voxelize_triangle(v, grid_, z0, z1, emit);
  }
}

void SurfaceVoxelizer::fill_chunk(std::int64_t chunk, BitVolume& out, std::int64_t z_origin) const {
  for_each_voxel(chunk, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    out.row(j, k - z_origin)[i >> 6] |= std::uint64_t{1} << (i & 63);
  });
}

void SurfaceVoxelizer::chunk_spans(std::int64_t chunk, std::vector<RowSpan>& out) const {
  const std::int64_t z0 = chunk * per_chunk_, ny = grid_.dims.y;
  // Voxels of a column along x come in order: they join the span before.
  for_each_voxel(chunk, [&](std::int64_t i, std::int64_t j, std::int64_t k) {
    const auto row = static_cast<std::uint32_t>((k - z0) * ny + j);
    const auto x = static_cast<std::uint32_t>(i);
    if (!out.empty() && out.back().row == row && out.back().end == x) {
      out.back().end = x + 1;
      return;
    }
    out.push_back({row, x, x + 1});
  });
}

}  // namespace detail

BitVolume voxelize_surface(const Mesh& mesh, const Grid& grid, int threads, JobControl* control) {
  BitVolume out(grid);
  const detail::SurfaceVoxelizer surface(mesh, grid, threads);
  const std::int64_t chunks = surface.chunk_count();
  std::atomic<std::int64_t> done{0};
  parallel_for(0, chunks, 1, surface.threads(), [&](std::int64_t c0, std::int64_t c1) {
    for (std::int64_t c = c0; c < c1; ++c) {
      if (control) control->check_cancelled();
      surface.fill_chunk(c, out);
      if (control) control->set_progress(static_cast<double>(done.fetch_add(1) + 1) / static_cast<double>(chunks));
    }
  });
  return out;
}

}  // namespace voxd
