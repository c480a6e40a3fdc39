// Convex pieces as polyhedra (a list of face polygons), clipped half-space
// by half-space; see voxd/voxelize/palette_geometry.h.
#include "voxd/voxelize/palette_geometry.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include <glm/geometric.hpp>

#include "voxd/error.h"

namespace voxd {
namespace {

// Distances below this (unit-voxel lengths) count as zero: a point this close
// to a plane is on it, two points this close are one.
constexpr double kEps = 1e-12;

using Polygon = std::vector<glm::dvec3>;  // convex, counter-clockwise seen from outside

struct Polyhedron {
  std::vector<Polygon> faces;
  bool empty() const { return faces.empty(); }
};

// A half-space n . p <= d with |n| = 1, so that n . p - d is a distance.
struct Plane {
  glm::dvec3 normal{0.0};
  double offset = 0.0;
  double distance(const glm::dvec3& p) const { return glm::dot(normal, p) - offset; }
};

// What a half-space does to whatever it is applied to.
enum class Cut { keep_all, keep_none, clip };

Cut normalize(const HalfSpace& h, Plane& plane) {
  const glm::dvec3& n = h.normal;
  if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z) || !std::isfinite(h.offset))
    throw Error(ErrorCode::invalid_argument, "palette element: a half-space has a non-finite normal or offset");
  const double length = glm::length(n);
  // A zero normal leaves 0 <= offset, true or false for every point.
  if (length == 0.0) return h.offset >= 0.0 ? Cut::keep_all : Cut::keep_none;
  plane.normal = n / length;
  plane.offset = h.offset / length;
  return Cut::clip;
}

Polyhedron unit_cube() {
  // Each face counter-clockwise seen from outside, i.e. around its outward normal.
  const auto v = [](int x, int y, int z) { return glm::dvec3(x, y, z); };
  return Polyhedron{{
      {v(0, 0, 0), v(0, 0, 1), v(0, 1, 1), v(0, 1, 0)},  // -x
      {v(1, 0, 0), v(1, 1, 0), v(1, 1, 1), v(1, 0, 1)},  // +x
      {v(0, 0, 0), v(1, 0, 0), v(1, 0, 1), v(0, 0, 1)},  // -y
      {v(0, 1, 0), v(0, 1, 1), v(1, 1, 1), v(1, 1, 0)},  // +y
      {v(0, 0, 0), v(0, 1, 0), v(1, 1, 0), v(1, 0, 0)},  // -z
      {v(0, 0, 1), v(1, 0, 1), v(1, 1, 1), v(0, 1, 1)},  // +z
  }};
}

bool lexicographically_less(const glm::dvec3& a, const glm::dvec3& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
}

// Where edge a-b crosses the plane. The endpoints are put in a fixed order
// first: the two faces sharing the edge walk it in opposite directions and
// must get the same point, bit for bit, or the mesh would not close.
glm::dvec3 crossing(glm::dvec3 a, double da, glm::dvec3 b, double db) {
  if (lexicographically_less(b, a)) {
    std::swap(a, b);
    std::swap(da, db);
  }
  return a + (b - a) * (da / (da - db));
}

bool same_point(const glm::dvec3& a, const glm::dvec3& b) { return glm::length(a - b) <= kEps; }

// Drops consecutive repeats (within kEps), also across the wrap-around.
void remove_repeats(Polygon& polygon) {
  Polygon out;
  out.reserve(polygon.size());
  for (const glm::dvec3& p : polygon)
    if (out.empty() || !same_point(out.back(), p)) out.push_back(p);
  while (out.size() > 1 && same_point(out.front(), out.back())) out.pop_back();
  polygon = std::move(out);
}

// Twice the area vector (Newell), pointing along the outward normal.
glm::dvec3 area_vector(const Polygon& polygon) {
  glm::dvec3 sum(0.0);
  for (std::size_t i = 0; i < polygon.size(); ++i)
    sum += glm::cross(polygon[i], polygon[(i + 1) % polygon.size()]);
  return sum;
}

// A polygon whose vertices are all (nearly) on one line. Relative to the
// perimeter, so that a small but proper face (a corner cut off close to the
// corner) is kept while rounding noise on a collinear one is not.
bool degenerate(const Polygon& polygon) {
  if (polygon.size() < 3) return true;
  double perimeter = 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i)
    perimeter += glm::length(polygon[(i + 1) % polygon.size()] - polygon[i]);
  return glm::length(area_vector(polygon)) <= kEps * perimeter * perimeter;
}

// Orders points of one plane counter-clockwise around its normal, by angle
// around their centroid (they are the vertices of a convex polygon).
void order_around(Polygon& points, const glm::dvec3& normal) {
  glm::dvec3 centre(0.0);
  for (const glm::dvec3& p : points) centre += p;
  centre /= static_cast<double>(points.size());
  // u, v, normal right-handed: increasing angle is counter-clockwise around the normal.
  const glm::dvec3 a = std::abs(normal.x) < 0.5 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  const glm::dvec3 u = glm::normalize(glm::cross(normal, a));
  const glm::dvec3 v = glm::cross(normal, u);
  std::vector<std::pair<double, glm::dvec3>> keyed;
  keyed.reserve(points.size());
  for (const glm::dvec3& p : points) keyed.emplace_back(std::atan2(glm::dot(p - centre, v), glm::dot(p - centre, u)), p);
  std::sort(keyed.begin(), keyed.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  for (std::size_t i = 0; i < points.size(); ++i) points[i] = keyed[i].second;
}

// The part of `poly` with plane.distance(p) <= 0: each face clipped
// (Sutherland-Hodgman with three states, so that vertices on the plane are
// kept once and never duplicated by a crossing), plus the cap closing the cut.
Polyhedron clip(const Polyhedron& poly, const Plane& plane) {
  bool any_outside = false, any_inside = false;
  for (const Polygon& face : poly.faces)
    for (const glm::dvec3& p : face) {
      const double d = plane.distance(p);
      any_outside |= d > kEps;
      any_inside |= d < -kEps;
    }
  // Nothing beyond the plane: untouched, even when a face lies in the plane
  // (no second, coincident cap).
  if (!any_outside) return poly;
  // Nothing strictly inside: at most a face or an edge is left, no volume.
  if (!any_inside) return {};

  Polyhedron out;
  Polygon on_plane;
  for (const Polygon& face : poly.faces) {
    Polygon kept;
    for (std::size_t i = 0; i < face.size(); ++i) {
      const glm::dvec3& a = face[i];
      const glm::dvec3& b = face[(i + 1) % face.size()];
      const double da = plane.distance(a), db = plane.distance(b);
      if (da <= kEps) {
        kept.push_back(a);
        if (da >= -kEps) on_plane.push_back(a);
      }
      if ((da < -kEps && db > kEps) || (da > kEps && db < -kEps)) {
        const glm::dvec3 p = crossing(a, da, b, db);
        kept.push_back(p);
        on_plane.push_back(p);
      }
    }
    remove_repeats(kept);
    if (!degenerate(kept)) out.faces.push_back(std::move(kept));
  }

  // The cap: each point on the plane was found once per face through it.
  Polygon cap;
  for (const glm::dvec3& p : on_plane)
    if (std::none_of(cap.begin(), cap.end(), [&](const glm::dvec3& q) { return same_point(p, q); })) cap.push_back(p);
  if (cap.size() >= 3) {
    order_around(cap, plane.normal);  // outward is +normal: the kept side is n . p <= d
    if (!degenerate(cap)) out.faces.push_back(std::move(cap));
  }
  return out;
}

double volume(const Polyhedron& poly) {
  double six_v = 0.0;
  for (const Polygon& face : poly.faces)
    for (std::size_t i = 1; i + 1 < face.size(); ++i)
      six_v += glm::dot(face[0], glm::cross(face[i], face[i + 1]));
  return six_v / 6.0;
}

// `poly` cut by every half-space of `piece`; empty when no volume is left.
Polyhedron clip_by(Polyhedron poly, const ConvexPiece& piece) {
  for (const HalfSpace& h : piece) {
    Plane plane;
    const Cut cut = normalize(h, plane);
    if (cut == Cut::keep_none) return {};
    if (cut == Cut::clip) poly = clip(poly, plane);
    if (poly.empty()) return {};
  }
  if (volume(poly) <= kEps) return {};
  return poly;
}

// Index of p among `vertices` from `first` on, appending it if new.
std::uint32_t weld(std::vector<glm::dvec3>& vertices, std::size_t first, const glm::dvec3& p) {
  for (std::size_t i = first; i < vertices.size(); ++i)
    if (same_point(vertices[i], p)) return static_cast<std::uint32_t>(i);
  vertices.push_back(p);
  return static_cast<std::uint32_t>(vertices.size() - 1);
}

bool degenerate_triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  return degenerate(Polygon{a, b, c});
}

void append_shell(const Polyhedron& poly, ElementMesh& mesh) {
  const std::size_t first = mesh.vertices.size();  // welding stays within this shell
  for (const Polygon& face : poly.faces) {
    std::vector<std::uint32_t> ids;
    ids.reserve(face.size());
    for (const glm::dvec3& p : face) ids.push_back(weld(mesh.vertices, first, p));
    // A fan from the first vertex, unless that makes a zero-area triangle
    // (collinear vertices along one side, left by a cut through a vertex):
    // then a fan from the centroid, which is strictly inside.
    bool fan_ok = true;
    for (std::size_t i = 1; i + 1 < face.size() && fan_ok; ++i)
      fan_ok = !degenerate_triangle(face[0], face[i], face[i + 1]);
    if (fan_ok) {
      for (std::size_t i = 1; i + 1 < face.size(); ++i) mesh.triangles.push_back({ids[0], ids[i], ids[i + 1]});
      continue;
    }
    glm::dvec3 centre(0.0);
    for (const glm::dvec3& p : face) centre += p;
    centre /= static_cast<double>(face.size());
    const std::uint32_t c = weld(mesh.vertices, first, centre);
    for (std::size_t i = 0; i < face.size(); ++i) {
      const std::size_t j = (i + 1) % face.size();
      if (!degenerate_triangle(centre, face[i], face[j])) mesh.triangles.push_back({c, ids[i], ids[j]});
    }
  }
}

// Inclusion-exclusion, depth first: `so_far` is the intersection of the
// pieces chosen so far (an odd number of them when `add`), extended by each
// later piece in turn.
struct UnionVolume {
  const std::vector<const ConvexPiece*>& pieces;
  std::size_t intersections = 0;
  double total = 0.0;

  void extend(const Polyhedron& so_far, std::size_t next, bool add) {
    for (std::size_t i = next; i < pieces.size(); ++i) {
      const Polyhedron both = clip_by(so_far, *pieces[i]);
      if (both.empty()) continue;  // and so is every intersection with more pieces
      if (++intersections > kMaxVolumeIntersections)
        throw Error(ErrorCode::limit_exceeded,
                    "palette element volume: more than " + std::to_string(kMaxVolumeIntersections) +
                        " overlapping piece intersections");
      const double v = volume(both);
      total += add ? v : -v;
      extend(both, i + 1, !add);
    }
  }
};

}  // namespace

ElementMesh element_mesh(const PaletteElement& element) {
  ElementMesh mesh;
  for (const ConvexPiece& piece : element.pieces) {
    const Polyhedron poly = clip_by(unit_cube(), piece);
    if (!poly.empty()) append_shell(poly, mesh);
  }
  return mesh;
}

double element_volume(const PaletteElement& element) {
  std::vector<const ConvexPiece*> pieces;
  pieces.reserve(element.pieces.size());
  for (const ConvexPiece& piece : element.pieces) pieces.push_back(&piece);
  UnionVolume sum{pieces};
  sum.extend(unit_cube(), 0, true);
  // Rounding may step past the bounds by an ulp; a share of the voxel never does.
  return std::clamp(sum.total, 0.0, 1.0);
}

}  // namespace voxd
