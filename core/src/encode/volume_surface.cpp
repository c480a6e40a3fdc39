#include "voxd/encode/volume_surface.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include "union_find.h"
#include "voxd/error.h"

namespace voxd {
namespace {

using Cell = glm::i64vec3;

// The six face directions: axis, then sign.
constexpr std::array<Cell, 6> kDirection = {Cell(1, 0, 0), Cell(-1, 0, 0), Cell(0, 1, 0),
                                            Cell(0, -1, 0), Cell(0, 0, 1), Cell(0, 0, -1)};
int direction_of(const Cell& d) {
  for (int i = 0; i < 6; ++i)
    if (kDirection[i] == d) return i;
  return -1;
}

bool filled(const BitVolume& v, const Cell& c) {
  const glm::i64vec3& n = v.grid().dims;
  return c.x >= 0 && c.y >= 0 && c.z >= 0 && c.x < n.x && c.y < n.y && c.z < n.z && v.get(c.x, c.y, c.z);
}

// A face's four corners, lattice points, counter-clockwise seen from
// outside: in the (u, w) plane of the two other axes, (u, w, axis) right-
// handed, reversed for a face towards -axis.
std::array<Cell, 4> corners(const Cell& voxel, int direction) {
  const int axis = direction / 2;
  const bool positive = direction % 2 == 0;
  const int u = (axis + 1) % 3, w = (axis + 2) % 3;
  Cell base = voxel;
  if (positive) base[axis] += 1;
  std::array<Cell, 4> c;
  const int order[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int i = 0; i < 4; ++i) {
    const int* o = order[positive ? i : (4 - i) % 4];
    c[i] = base;
    c[i][u] += o[0];
    c[i][w] += o[1];
  }
  return c;
}

}  // namespace

std::uint64_t boundary_face_count(const BitVolume& volume) {
  const glm::i64vec3& n = volume.grid().dims;
  std::uint64_t faces = 0;
  for (std::int64_t k = 0; k < n.z; ++k)
    for (std::int64_t j = 0; j < n.y; ++j)
      for (std::int64_t i = 0; i < n.x; ++i) {
        if (!volume.get(i, j, k)) continue;
        for (const Cell& d : kDirection) faces += !filled(volume, Cell(i, j, k) + d);
      }
  return faces;
}

namespace {

// The surface's faces and how their corners join into vertices, given the
// lattice edges where two voxels meet only along the edge and the surface
// joins the faces round each empty voxel there instead of round each filled
// one (`crossed`).
struct VoxelSurfaceBuilder {
  const BitVolume& volume;
  glm::i64vec3 n;
  std::vector<std::uint64_t> keys;  // voxel index * 6 + direction, sorted
  std::vector<Cell> voxel_of;

  explicit VoxelSurfaceBuilder(const BitVolume& v) : volume(v), n(v.grid().dims) {
    for (std::int64_t k = 0; k < n.z; ++k)
      for (std::int64_t j = 0; j < n.y; ++j)
        for (std::int64_t i = 0; i < n.x; ++i) {
          if (!volume.get(i, j, k)) continue;
          for (int d = 0; d < 6; ++d)
            if (!filled(volume, Cell(i, j, k) + kDirection[d])) {
              keys.push_back(key(Cell(i, j, k), d));
              voxel_of.push_back(Cell(i, j, k));
            }
        }
    if (4 * keys.size() > std::numeric_limits<std::uint32_t>::max())
      throw Error(ErrorCode::limit_exceeded, "the voxel surface has " + std::to_string(keys.size()) +
                                                 " faces, more than a mesh's 32-bit indices can number");
  }

  std::uint64_t key(const Cell& c, int d) const {
    return (static_cast<std::uint64_t>(c.x) +
            static_cast<std::uint64_t>(n.x) * (static_cast<std::uint64_t>(c.y) + static_cast<std::uint64_t>(n.y) *
                                                                                   static_cast<std::uint64_t>(c.z))) *
               6 +
           static_cast<std::uint64_t>(d);
  }
  std::uint32_t face_index(const Cell& c, int d) const {
    return static_cast<std::uint32_t>(std::lower_bound(keys.begin(), keys.end(), key(c, d)) - keys.begin());
  }
  // A lattice edge by its lower end (lattice points run 0..n) and axis.
  std::uint64_t edge_key(const Cell& p, const Cell& q) const {
    const Cell lo = glm::min(p, q);
    const int axis = p.x != q.x ? 0 : p.y != q.y ? 1 : 2;
    return ((static_cast<std::uint64_t>(lo.x) * static_cast<std::uint64_t>(n.y + 1) + static_cast<std::uint64_t>(lo.y)) *
                static_cast<std::uint64_t>(n.z + 1) + static_cast<std::uint64_t>(lo.z)) * 3 + static_cast<std::uint64_t>(axis);
  }

  // Each face's corners are nodes (face * 4 + corner); the corners of two
  // faces that continue each other across an edge are one vertex. Across an
  // edge a face continues (6-connected surface tracking):
  //  - round the voxel's own convex edge, when the voxel beside it (v + b)
  //    is empty, even if the one diagonally beyond is filled: voxels that
  //    meet along an edge only stay apart (unless the edge is `crossed`);
  //  - flat onto the neighbour's face, when v + b is filled and v + b + d
  //    empty;
  //  - into the concave corner, onto the face of v + b + d towards -b.
  Mesh build(const std::unordered_set<std::uint64_t>& crossed, std::vector<Cell>& vertex_point) const {
    detail::UnionFind nodes(4 * keys.size());
    for (std::uint32_t f = 0; f < keys.size(); ++f) {
      const Cell v = voxel_of[f];
      const int d = static_cast<int>(keys[f] % 6);
      const std::array<Cell, 4> mine = corners(v, d);
      for (int e = 0; e < 4; ++e) {
        const Cell p = mine[e], q = mine[(e + 1) % 4];
        // b: from the face's middle across this edge, within its plane.
        const Cell b = (p + q) - (mine[0] + mine[2]);
        const Cell dv = kDirection[d];
        Cell partner_voxel;
        int partner_direction;
        const bool beside = filled(volume, v + b), diagonal = filled(volume, v + b + dv);
        if (!beside && !(diagonal && crossed.count(edge_key(p, q)))) {
          partner_voxel = v, partner_direction = direction_of(b);
        } else if (beside && !diagonal) {
          partner_voxel = v + b, partner_direction = d;
        } else {
          partner_voxel = v + b + dv, partner_direction = direction_of(-b);
        }
        const std::uint32_t g = face_index(partner_voxel, partner_direction);
        const std::array<Cell, 4> theirs = corners(partner_voxel, partner_direction);
        for (int c = 0; c < 4; ++c) {
          if (theirs[c] == p) nodes.join(4 * f + e, 4 * g + c);
          if (theirs[c] == q) nodes.join(4 * f + (e + 1) % 4, 4 * g + c);
        }
      }
    }
    const Grid& grid = volume.grid();
    Mesh mesh;
    vertex_point.clear();
    std::vector<std::uint32_t> vertex_of(4 * keys.size(), std::numeric_limits<std::uint32_t>::max());
    mesh.triangles.resize(2 * keys.size());
    for (std::uint32_t f = 0; f < keys.size(); ++f) {
      const std::array<Cell, 4> c = corners(voxel_of[f], static_cast<int>(keys[f] % 6));
      std::array<std::uint32_t, 4> id;
      for (int i = 0; i < 4; ++i) {
        std::uint32_t& vertex = vertex_of[nodes.find(4 * f + i)];
        if (vertex == std::numeric_limits<std::uint32_t>::max()) {
          vertex = static_cast<std::uint32_t>(mesh.vertices.size());
          mesh.vertices.push_back(glm::vec3(grid.origin + glm::dvec3(c[i]) * grid.voxel_size));
          vertex_point.push_back(c[i]);
        }
        id[i] = vertex;
      }
      mesh.triangles[2 * f] = {id[0], id[1], id[2]};
      mesh.triangles[2 * f + 1] = {id[0], id[2], id[3]};
    }
    return mesh;
  }
};

}  // namespace

Mesh voxel_surface(const BitVolume& volume) {
  const VoxelSurfaceBuilder builder(volume);
  // Keeping voxels that meet along an edge apart leaves the surface pinched
  // where one sheet passes such an edge twice, joined round both its ends
  // (the edge then in four triangles): there the sheet is joined round the
  // empty voxels instead, which parts it, and the surface made again.
  std::unordered_set<std::uint64_t> crossed;
  std::vector<Cell> point;
  for (int round = 0;; ++round) {
    Mesh mesh = builder.build(crossed, point);
    std::unordered_map<std::uint64_t, int> uses;  // directed vertex pair
    std::unordered_set<std::uint64_t> pinched;  // lattice edges
    for (const auto& t : mesh.triangles)
      for (int e = 0; e < 3; ++e)
        if (++uses[(static_cast<std::uint64_t>(t[e]) << 32) | t[(e + 1) % 3]] == 2)
          pinched.insert(builder.edge_key(point[t[e]], point[t[(e + 1) % 3]]));
    if (pinched.empty() || round == 8) return mesh;
    for (const std::uint64_t e : pinched) {
      if (!crossed.insert(e).second) crossed.erase(e);
    }
  }
}

Mesh zero_level_set(const DenseVolume<float>& sdf, bool inside_negative, float outside) {
  const Grid& g = sdf.grid();
  // Samples of the padded grid (one sample of outside all round): p = the
  // grid's sample + 1. Inside reads negative whatever the convention.
  const glm::i64vec3 n = g.dims + glm::i64vec3(2);
  const float sign = inside_negative ? 1.0f : -1.0f;
  auto field = [&](std::int64_t i, std::int64_t j, std::int64_t k) -> float {
    if (i < 1 || j < 1 || k < 1 || i > g.dims.x || j > g.dims.y || k > g.dims.z) return outside;
    const float v = sign * sdf.at(i - 1, j - 1, k - 1);
    return v == 0.0f ? 0.0f : v;  // -0 is on the surface, as +0: outside
  };
  const std::int64_t cx = n.x - 1, cy = n.y - 1, cz = n.z - 1;  // cells a side
  Mesh mesh;
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  // The cells' vertices two z layers at a time: quads join cells of layers
  // k - 1 and k only.
  std::vector<std::uint32_t> below(static_cast<std::size_t>(cx * cy), kNone), here(below.size(), kNone);
  static constexpr int kEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                        {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  auto quad = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d, bool flip) {
    if (flip) {
      mesh.triangles.push_back({a, c, b});
      mesh.triangles.push_back({a, d, c});
    } else {
      mesh.triangles.push_back({a, b, c});
      mesh.triangles.push_back({a, c, d});
    }
  };
  const auto at = [&](const std::vector<std::uint32_t>& layer, std::int64_t i, std::int64_t j) {
    return layer[static_cast<std::size_t>(i + cx * j)];
  };
  for (std::int64_t k = 0; k < cz; ++k) {
    std::fill(here.begin(), here.end(), kNone);
    for (std::int64_t j = 0; j < cy; ++j)
      for (std::int64_t i = 0; i < cx; ++i) {
        float corner[8];
        int negative = 0;
        for (int c = 0; c < 8; ++c) {
          corner[c] = field(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
          negative += corner[c] < 0;
        }
        if (negative == 0 || negative == 8) continue;
        glm::dvec3 sum(0.0);
        int crossings = 0;
        for (const auto& [a, b] : kEdges) {
          if ((corner[a] < 0) == (corner[b] < 0)) continue;
          const double t = corner[a] / (static_cast<double>(corner[a]) - corner[b]);
          const glm::dvec3 pa(a & 1, (a >> 1) & 1, (a >> 2) & 1), pb(b & 1, (b >> 1) & 1, (b >> 2) & 1);
          sum += pa + t * (pb - pa);
          ++crossings;
        }
        // Padded sample p sits at grid voxel p - 1, whose centre is p - 1/2.
        const glm::dvec3 p = glm::dvec3(i, j, k) - 0.5 + sum / static_cast<double>(crossings);
        here[static_cast<std::size_t>(i + cx * j)] = static_cast<std::uint32_t>(mesh.vertices.size());
        mesh.vertices.push_back(glm::vec3(g.origin + p * g.voxel_size));
      }
    // Edges along z from sample layer k: the four cells of layer k round it.
    for (std::int64_t j = 1; j < cy; ++j)
      for (std::int64_t i = 1; i < cx; ++i) {
        const float f0 = field(i, j, k), f1 = field(i, j, k + 1);
        if ((f0 < 0) == (f1 < 0)) continue;
        quad(at(here, i - 1, j - 1), at(here, i, j - 1), at(here, i, j), at(here, i - 1, j), f0 >= 0);
      }
    // Edges along x and y in sample layer k: cells of layers k - 1 and k.
    if (k >= 1) {
      for (std::int64_t j = 1; j < cy; ++j)
        for (std::int64_t i = 0; i < cx; ++i) {
          const float f0 = field(i, j, k), f1 = field(i + 1, j, k);
          if ((f0 < 0) == (f1 < 0)) continue;
          quad(at(below, i, j - 1), at(below, i, j), at(here, i, j), at(here, i, j - 1), f0 >= 0);
        }
      for (std::int64_t j = 0; j < cy; ++j)
        for (std::int64_t i = 1; i < cx; ++i) {
          const float f0 = field(i, j, k), f1 = field(i, j + 1, k);
          if ((f0 < 0) == (f1 < 0)) continue;
          quad(at(below, i - 1, j), at(here, i - 1, j), at(here, i, j), at(below, i, j), f0 >= 0);
        }
    }
    std::swap(below, here);
  }
  return mesh;
}

}  // namespace voxd
