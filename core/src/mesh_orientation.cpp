// Orientation repair (voxd/mesh_orientation.h). Edges are grouped as the mesh
// report groups them, by a counting sort on their smaller welded vertex; each
// manifold edge links its two triangles with whether they agree, and a
// breadth-first walk over those links gives every triangle a flip relative to
// its component's seed.
#include "voxd/mesh_orientation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>

#include "voxd/mesh_report.h"

namespace voxd {
namespace {

constexpr std::uint32_t kNone = ~std::uint32_t{0};

bool repeats_a_vertex(const std::array<std::uint32_t, 3>& t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; }

// A manifold edge's two triangles, and whether they traverse it in the same
// direction (then one of them must turn).
struct Link {
  std::uint32_t a, b;
  bool same_direction;
};

struct EdgeUse {
  std::uint64_t key;  // larger vertex << 1 | 1 if traversed from smaller to larger
  std::uint32_t triangle;
};

std::vector<Link> manifold_links(const Mesh& welded, OrientationRepair& repair) {
  const std::size_t vertex_count = welded.vertices.size();
  std::vector<std::size_t> start(vertex_count + 1, 0);
  for (const auto& t : welded.triangles) {
    if (repeats_a_vertex(t)) continue;
    for (int c = 0; c < 3; ++c) ++start[std::min(t[c], t[(c + 1) % 3]) + 1];
  }
  for (std::size_t v = 0; v < vertex_count; ++v) start[v + 1] += start[v];
  std::vector<EdgeUse> uses(start[vertex_count]);
  std::vector<std::size_t> cursor(start.begin(), start.end() - 1);
  for (std::uint32_t i = 0; i < welded.triangles.size(); ++i) {
    const auto& t = welded.triangles[i];
    if (repeats_a_vertex(t)) continue;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t from = t[c], to = t[(c + 1) % 3];
      const std::uint32_t low = std::min(from, to), high = std::max(from, to);
      uses[cursor[low]++] = {std::uint64_t{high} << 1 | (from == low ? 1u : 0u), i};
    }
  }
  std::vector<Link> links;
  links.reserve(uses.size() / 2);
  for (std::size_t v = 0; v < vertex_count; ++v) {
    EdgeUse* first = uses.data() + start[v];
    EdgeUse* const last = uses.data() + start[v + 1];
    std::sort(first, last, [](const EdgeUse& x, const EdgeUse& y) { return x.key < y.key; });
    while (first < last) {
      EdgeUse* end = first;
      while (end < last && (end->key >> 1) == (first->key >> 1)) ++end;
      const std::ptrdiff_t count = end - first;
      if (count == 1) ++repair.boundary_edges;
      else if (count > 2) ++repair.nonmanifold_edges;
      else {
        links.push_back({first[0].triangle, first[1].triangle, (first[0].key & 1) == (first[1].key & 1)});
        if (links.back().same_direction) ++repair.inconsistent_edges;
      }
      first = end;
    }
  }
  return links;
}

struct Component {
  std::vector<std::uint32_t> triangles;
  Aabb box;
  double area = 0.0;
  double six_volume = 0.0;    // about the area-weighted centroid, as oriented by the walk
  bool closed = true;         // no boundary or non-manifold edge (set from the walk)
  bool has_sign = false;      // closed, or open with a clear signed volume
  glm::dvec3 probe{0.0};      // a point on its largest triangle, for ray parity
  int depth = 0;              // how many signed components enclose it
  std::uint32_t parent = kNone;  // the smallest of those
  bool invert = false;
};

glm::dvec3 corner(const Mesh& m, std::uint32_t t, int c) { return glm::dvec3(m.vertices[m.triangles[t][c]]); }

// Crossings of the ray from p along `d` with the component's triangles
// (Moeller-Trumbore in double): odd when p is enclosed by a closed
// component.
int crossings(const Mesh& m, const std::vector<std::uint32_t>& tris, glm::dvec3 p, glm::dvec3 d) {
  int count = 0;
  for (std::uint32_t t : tris) {
    const glm::dvec3 a = corner(m, t, 0), b = corner(m, t, 1), c = corner(m, t, 2);
    const glm::dvec3 e1 = b - a, e2 = c - a;
    const glm::dvec3 q = glm::cross(d, e2);
    const double det = glm::dot(e1, q);
    if (det == 0.0) continue;
    const double inv = 1.0 / det;
    const glm::dvec3 s = p - a;
    const double u = glm::dot(s, q) * inv;
    if (u < 0.0 || u > 1.0) continue;
    const glm::dvec3 r = glm::cross(s, e1);
    const double v = glm::dot(d, r) * inv;
    if (v < 0.0 || u + v > 1.0) continue;
    if (glm::dot(e2, r) * inv > 0.0) ++count;
  }
  return count;
}

// Whether p is inside the component: odd crossings along most of three
// rays, in directions that keep off the edges and vertices of axis-aligned
// and grid-like meshes. Three rays, not one, because an enclosure may be
// open: a ray that leaves through a hole would say outside.
bool encloses(const Mesh& m, const std::vector<std::uint32_t>& tris, glm::dvec3 p) {
  static const glm::dvec3 kDirections[3] = {glm::normalize(glm::dvec3(1.0, 0.5772156649, 0.3183098862)),
                                            glm::normalize(glm::dvec3(-0.4142135624, 1.0, -0.7071067812)),
                                            glm::normalize(glm::dvec3(0.2718281828, -0.6180339887, 1.0))};
  int odd = 0;
  for (const glm::dvec3& d : kDirections) odd += crossings(m, tris, p, d) % 2;
  return odd >= 2;
}

bool box_contains(const Aabb& outer, const Aabb& inner) {
  return outer.min.x <= inner.min.x && outer.min.y <= inner.min.y && outer.min.z <= inner.min.z &&
         outer.max.x >= inner.max.x && outer.max.y >= inner.max.y && outer.max.z >= inner.max.z;
}

double box_volume(const Aabb& b) {
  const glm::dvec3 e = b.extent();
  return e.x * e.y * e.z;
}

// Past this many signed components the nesting test (pairs of boxes) is
// skipped and every component is taken to be enclosed by none.
constexpr std::size_t kMaxNestingComponents = 4096;
// An open component's signed volume, against its area times its size, above
// which it is taken to enclose a side (a hemisphere gives about 0.05, a
// closed sphere 0.1; a sheet bent by a few degrees stays well under).
constexpr double kOpenSignedFraction = 0.01;

}  // namespace

OrientationRepair orient_outward(Mesh& mesh) {
  OrientationRepair repair;
  if (mesh.triangles.empty()) return repair;
  const Mesh welded = weld_vertices(mesh);
  const std::vector<Link> links = manifold_links(welded, repair);
  const std::size_t n = welded.triangles.size();

  // Links of each triangle, as (other triangle << 1 | same direction).
  std::vector<std::uint32_t> first(n + 1, 0);
  for (const Link& l : links) {
    ++first[l.a + 1];
    ++first[l.b + 1];
  }
  std::partial_sum(first.begin(), first.end(), first.begin());
  std::vector<std::uint64_t> adjacent(first[n]);
  {
    std::vector<std::uint32_t> at(first.begin(), first.end() - 1);
    for (const Link& l : links) {
      adjacent[at[l.a]++] = std::uint64_t{l.b} << 1 | l.same_direction;
      adjacent[at[l.b]++] = std::uint64_t{l.a} << 1 | l.same_direction;
    }
  }
  // Which triangles have an edge that is not a manifold link (boundary or
  // non-manifold): their components are open.
  std::vector<std::uint8_t> open_edge(n, 0);
  for (std::uint32_t t = 0; t < n; ++t)
    if (!repeats_a_vertex(welded.triangles[t]) && first[t + 1] - first[t] < 3) open_edge[t] = 1;

  std::vector<std::uint8_t> flip(n, 0);
  std::vector<std::uint32_t> component_of(n, kNone);
  std::vector<Component> components;
  std::vector<std::uint32_t> queue;
  for (std::uint32_t seed = 0; seed < n; ++seed) {
    if (component_of[seed] != kNone || repeats_a_vertex(welded.triangles[seed])) continue;
    const auto id = static_cast<std::uint32_t>(components.size());
    Component c;
    queue.assign(1, seed);
    component_of[seed] = id;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::uint32_t t = queue[head];
      c.triangles.push_back(t);
      if (open_edge[t]) c.closed = false;
      for (std::uint32_t k = first[t]; k < first[t + 1]; ++k) {
        const auto u = static_cast<std::uint32_t>(adjacent[k] >> 1);
        const std::uint8_t want = flip[t] ^ static_cast<std::uint8_t>(adjacent[k] & 1);
        if (component_of[u] == kNone) {
          component_of[u] = id;
          flip[u] = want;
          queue.push_back(u);
        } else if (flip[u] != want && t < u) {
          ++repair.unorientable_edges;
        }
      }
    }
    components.push_back(std::move(c));
  }

  // Each component as most of its area was written; then its geometry.
  for (Component& c : components) {
    double flipped_area = 0.0;
    glm::dvec3 weighted(0.0);
    double largest = -1.0;
    c.box = {glm::dvec3(std::numeric_limits<double>::max()), glm::dvec3(std::numeric_limits<double>::lowest())};
    for (std::uint32_t t : c.triangles) {
      const glm::dvec3 a = corner(welded, t, 0), b = corner(welded, t, 1), d = corner(welded, t, 2);
      const double area = glm::length(glm::cross(b - a, d - a)) / 2.0;
      c.area += area;
      if (flip[t]) flipped_area += area;
      weighted += area * (a + b + d) / 3.0;
      for (const glm::dvec3& p : {a, b, d}) {
        c.box.min = glm::min(c.box.min, p);
        c.box.max = glm::max(c.box.max, p);
      }
      if (area > largest) {
        largest = area;
        c.probe = (a + b + d) / 3.0;
      }
    }
    if (c.area == 0.0) continue;
    if (flipped_area > c.area / 2.0)
      for (std::uint32_t t : c.triangles) flip[t] ^= 1;
    const glm::dvec3 centroid = weighted / c.area;
    for (std::uint32_t t : c.triangles) {
      const glm::dvec3 a = corner(welded, t, 0), b = corner(welded, t, 1), d = corner(welded, t, 2);
      const double term = glm::dot(a - centroid, glm::cross(b - a, d - a));
      c.six_volume += flip[t] ? -term : term;
    }
    const double size = glm::length(c.box.extent());
    c.has_sign = c.closed ? c.six_volume != 0.0 : std::abs(c.six_volume) / 6.0 > kOpenSignedFraction * c.area * size;
  }

  // Nesting: how many signed components enclose each one, larger boxes first.
  std::vector<std::uint32_t> signed_ids;
  for (std::uint32_t i = 0; i < components.size(); ++i)
    if (components[i].area > 0.0) ++repair.components;
  for (std::uint32_t i = 0; i < components.size(); ++i)
    if (components[i].has_sign) signed_ids.push_back(i);
  std::sort(signed_ids.begin(), signed_ids.end(), [&](std::uint32_t x, std::uint32_t y) {
    return box_volume(components[x].box) > box_volume(components[y].box);
  });
  if (signed_ids.size() <= kMaxNestingComponents) {
    for (std::size_t i = 0; i < signed_ids.size(); ++i) {
      Component& inner = components[signed_ids[i]];
      for (std::size_t j = 0; j < i; ++j) {
        const Component& outer = components[signed_ids[j]];
        if (!box_contains(outer.box, inner.box)) continue;
        if (encloses(welded, outer.triangles, inner.probe)) {
          ++inner.depth;
          inner.parent = signed_ids[j];  // later (smaller) enclosing boxes replace earlier ones
        }
      }
    }
  }
  // Outermost first: a component at even depth is a solid (positive); at odd
  // depth a negative one is a cavity, and a positive one is either a solid
  // set inside another or a cavity written inside out, which follows its
  // enclosure: turned when that was.
  for (std::uint32_t id : signed_ids) {
    Component& c = components[id];
    if (c.depth % 2 == 0)
      c.invert = c.six_volume < 0.0;
    else
      c.invert = c.six_volume > 0.0 && c.parent != kNone && components[c.parent].invert;
    if (c.invert) ++repair.inverted_components;
  }

  // Count and apply: a triangle turned by the walk and by its component's
  // sign ends up as written.
  for (const Component& c : components) {
    for (std::uint32_t t : c.triangles) {
      const bool turned_by_walk = flip[t] != 0;
      if (turned_by_walk) ++repair.inconsistent_triangles;
      if (turned_by_walk != c.invert) {
        ++repair.flipped_triangles;
        std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
      }
    }
  }
  return repair;
}

}  // namespace voxd
