#include "support/test_parts.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

#include <glm/geometric.hpp>

#include "support/test_meshes.h"

namespace voxd::test {
namespace {

constexpr double kPi = std::numbers::pi;

// The area of a regular n-gon of circumradius 1.
double ngon_area_factor(int n) { return 0.5 * n * std::sin(2.0 * kPi / n); }

std::uint32_t add_vertex(Mesh& m, glm::dvec3 p) {
  m.vertices.emplace_back(p);
  return static_cast<std::uint32_t>(m.vertices.size() - 1);
}

void add_triangle(Mesh& m, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  if (a == b || b == c || c == a) return;  // a corner on the axis
  m.triangles.push_back({a, b, c});
}

// The quad a-b-c-d, counter-clockwise seen from outside.
void add_quad(Mesh& m, std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
  add_triangle(m, a, b, c);
  add_triangle(m, a, c, d);
}

glm::dvec3 on_circle(double r, double angle, double z) { return {r * std::cos(angle), r * std::sin(angle), z}; }

}  // namespace

Mesh make_lathe(const std::vector<glm::dvec2>& profile, int segments) {
  Mesh m;
  const std::size_t p = profile.size();
  // rings[i][s]: profile point i turned s steps (one vertex where r = 0).
  std::vector<std::vector<std::uint32_t>> rings(p);
  for (std::size_t i = 0; i < p; ++i) {
    const glm::dvec2 q = profile[i];
    if (q.x < 0.0) throw std::invalid_argument("make_lathe: a profile point has r < 0");
    if (q.x == 0.0) {
      rings[i].assign(static_cast<std::size_t>(segments), add_vertex(m, {0.0, 0.0, q.y}));
      continue;
    }
    for (int s = 0; s < segments; ++s) rings[i].push_back(add_vertex(m, on_circle(q.x, 2.0 * kPi * s / segments, q.y)));
  }
  for (std::size_t i = 0; i < p; ++i) {
    const std::size_t j = (i + 1) % p;
    for (int s = 0; s < segments; ++s) {
      const auto s0 = static_cast<std::size_t>(s), s1 = static_cast<std::size_t>((s + 1) % segments);
      // Profile point i at steps s and s+1, then point j: outward, as the
      // profile runs counter-clockwise.
      add_quad(m, rings[i][s0], rings[i][s1], rings[j][s1], rings[j][s0]);
    }
  }
  return m;
}

double lathe_volume(const std::vector<glm::dvec2>& profile, int segments) {
  double sum = 0.0;
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const glm::dvec2 a = profile[i], b = profile[(i + 1) % profile.size()];
    sum += (b.y - a.y) * (a.x * a.x + a.x * b.x + b.x * b.x) / 3.0;
  }
  return ngon_area_factor(segments) * sum;
}

double lathe_area(const std::vector<glm::dvec2>& profile, int segments) {
  // Each edge sweeps `segments` trapezoids: parallel sides 2 r sin(pi/n),
  // apart by the edge's length with dr shortened to the apothems' cos(pi/n).
  const double half = kPi / segments;
  double sum = 0.0;
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const glm::dvec2 a = profile[i], b = profile[(i + 1) % profile.size()];
    const double dz = b.y - a.y, dr = (b.x - a.x) * std::cos(half);
    sum += (a.x + b.x) * std::sin(half) * std::sqrt(dz * dz + dr * dr);
  }
  return segments * sum;
}

Part make_hex_nut(double across_flats, double bore, double height, int bore_segments) {
  if (bore_segments % 12 != 0) throw std::invalid_argument("make_hex_nut: bore_segments must be a multiple of 12");
  const int n = bore_segments;
  const double apothem = across_flats / 2.0, r = bore / 2.0;
  Mesh m;
  // Outer (on the hexagon, whose corners fall on steps at 30 + 60k degrees)
  // and inner (on the bore) points at the same angles, bottom and top.
  std::vector<std::uint32_t> ob, ot, ib, it;
  for (int s = 0; s < n; ++s) {
    const double angle = 2.0 * kPi * s / n;
    const double flat = std::round(angle / (kPi / 3.0)) * (kPi / 3.0);  // the nearest flat's normal
    const double rho = apothem / std::cos(angle - flat);
    ob.push_back(add_vertex(m, on_circle(rho, angle, 0.0)));
    ot.push_back(add_vertex(m, on_circle(rho, angle, height)));
    ib.push_back(add_vertex(m, on_circle(r, angle, 0.0)));
    it.push_back(add_vertex(m, on_circle(r, angle, height)));
  }
  for (int s = 0; s < n; ++s) {
    const auto a = static_cast<std::size_t>(s), b = static_cast<std::size_t>((s + 1) % n);
    add_quad(m, ob[a], ob[b], ot[b], ot[a]);  // flats, facing out
    add_quad(m, ib[a], it[a], it[b], ib[b]);  // bore, facing the axis
    add_quad(m, ot[a], ot[b], it[b], it[a]);  // top, facing +z
    add_quad(m, ob[a], ib[a], ib[b], ob[b]);  // bottom, facing -z
  }
  const double hexagon = 2.0 * std::sqrt(3.0) * apothem * apothem;
  const double hole = ngon_area_factor(n) * r * r;
  const double side = across_flats / std::sqrt(3.0);
  Part part;
  part.name = "hex_nut.stl";
  part.mesh = std::move(m);
  part.volume = height * (hexagon - hole);
  part.surface_area = 2.0 * (hexagon - hole) + height * 6.0 * side + height * n * 2.0 * r * std::sin(kPi / n);
  if (height > apothem - r) throw std::invalid_argument("make_hex_nut: a nut this high has its ring as its wall");
  part.thinnest_wall = height;  // a plate thinner than its ring: the height everywhere
  part.largest_ball = height;
  part.genus = 1;
  return part;
}

namespace {

Part lathe_part(std::string name, const std::vector<glm::dvec2>& profile, int segments) {
  Part part;
  part.name = std::move(name);
  part.mesh = make_lathe(profile, segments);
  part.volume = lathe_volume(profile, segments);
  part.surface_area = lathe_area(profile, segments);
  return part;
}

}  // namespace

Part make_screw(int segments) {
  // The ISO metric basic profile of M3: pitch P, fundamental triangle
  // H = P sqrt(3) / 2, thread depth 5H/8, crest flat P/8, root flat P/4.
  const double crest = 1.5, pitch = 0.5, length = 10.0;
  const double depth = 5.0 / 8.0 * pitch * std::sqrt(3.0) / 2.0, core = crest - depth;
  const double flank = depth * std::tan(kPi / 6.0);  // 60-degree flanks: along z per side
  std::vector<glm::dvec2> profile = {{0.0, 0.0}, {crest, 0.0}};
  for (int k = 0; k < static_cast<int>(std::lround(length / pitch)); ++k) {
    const double z = k * pitch + pitch / 8.0;  // past the crest's flat
    profile.push_back({crest, z});
    profile.push_back({core, z + flank});
    profile.push_back({core, z + flank + pitch / 4.0});
    profile.push_back({crest, z + 2.0 * flank + pitch / 4.0});  // = the next tooth's start
  }
  const double head_radius = 2.75, head = 3.0;
  profile.push_back({head_radius, length});
  profile.push_back({head_radius, length + head});
  profile.push_back({0.0, length + head});
  Part part = lathe_part("screw.stl", profile, segments);
  part.thinnest_wall = 2.0 * core;
  // On the axis, touching the head's top and the shank's rim under it:
  // rho^2 = crest^2 + (head - rho)^2.
  part.largest_ball = 2.0 * (crest * crest + head * head) / (2.0 * head);
  return part;
}

Part make_flanged_bushing(int segments) {
  const double bore = 3.0, outside = 4.0, height = 10.0, flange = 8.0, flange_height = 1.5;
  Part part = lathe_part("flanged_bushing.stl",
                         {{bore, 0.0}, {flange, 0.0}, {flange, flange_height}, {outside, flange_height},
                          {outside, height}, {bore, height}},
                         segments);
  part.thinnest_wall = outside - bore;
  // In the corner where the tube meets the flange: touching the bore, the
  // flange's bottom and the inner corner's ring, (a - rho)^2 + (b - rho)^2 = rho^2.
  const double a = outside - bore, b = flange_height;
  part.largest_ball = 2.0 * (a + b - std::sqrt(2.0 * a * b));
  part.genus = 1;
  return part;
}

Part make_disk(int segments) {
  const double radius = 7.5, thickness = 0.2;
  Part part = lathe_part("disk.stl", {{0.0, 0.0}, {radius, 0.0}, {radius, thickness}, {0.0, thickness}}, segments);
  part.thinnest_wall = thickness;
  part.largest_ball = thickness;
  return part;
}

Part make_torus_part() {
  const double R = 11.44, r = 2.83;
  const int around = 64, across = 24;
  std::vector<glm::dvec2> profile;
  for (int j = 0; j < across; ++j) {
    const double w = 2.0 * kPi * j / across;
    profile.push_back({R + r * std::cos(w), r + r * std::sin(w)});
  }
  Part part = lathe_part("torus.stl", profile, around);
  part.thinnest_wall = 2.0 * r;
  part.largest_ball = 2.0 * r;
  part.genus = 1;
  return part;
}

Part make_blob(int level) {
  Mesh m = make_icosphere({0, 0, 0}, 1.0, level);
  for (auto& v : m.vertices) {
    const glm::dvec3 d = glm::normalize(glm::dvec3(v));
    const double bump = 1.0 + 0.22 * std::sin(3.0 * d.x + 1.0) * std::cos(2.0 * d.y) + 0.15 * std::sin(5.0 * d.z + 0.5) +
                        0.1 * std::cos(4.0 * d.x * d.y + 2.0 * d.z);
    v = glm::vec3(d * bump);
  }
  // Stretched onto the bunny's box.
  const glm::dvec3 lo(-23.89, -41.43, 5.25), hi(84.23, 45.2, 112.51);
  const Aabb box = bounds(m);
  for (auto& v : m.vertices) v = glm::vec3(lo + (glm::dvec3(v) - box.min) / box.extent() * (hi - lo));
  Part part;
  part.name = "blob.stl";
  part.volume = mesh_volume(m);
  part.surface_area = mesh_area(m);
  part.mesh = std::move(m);
  return part;
}

namespace {

// Each part's file name and its maker (defaults for every argument).
const std::vector<std::pair<std::string, Part (*)()>>& part_makers() {
  static const std::vector<std::pair<std::string, Part (*)()>> makers = {
      {"hex_nut.stl", [] { return make_hex_nut(); }},
      {"screw.stl", [] { return make_screw(); }},
      {"flanged_bushing.stl", [] { return make_flanged_bushing(); }},
      {"disk.stl", [] { return make_disk(); }},
      {"torus.stl", make_torus_part},
      {"blob.stl", [] { return make_blob(); }},
  };
  return makers;
}

}  // namespace

std::vector<Part> all_parts() {
  std::vector<Part> parts;
  for (const auto& [name, make] : part_makers()) parts.push_back(make());
  return parts;
}

Part part_named(const std::string& name) {
  for (const auto& [file, make] : part_makers())
    if (file == name) return make();
  throw std::invalid_argument("no test part named " + name);
}

double mesh_area(const Mesh& mesh) {
  double area = 0.0;
  for (const auto& t : mesh.triangles) {
    const glm::dvec3 a(mesh.vertices[t[0]]), b(mesh.vertices[t[1]]), c(mesh.vertices[t[2]]);
    area += 0.5 * glm::length(glm::cross(b - a, c - a));
  }
  return area;
}

}  // namespace voxd::test
