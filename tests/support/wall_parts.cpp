#include "support/wall_parts.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "support/test_meshes.h"
#include "support/test_parts.h"

namespace voxd::test {
namespace {

constexpr double kPi = std::numbers::pi;

// Points of a quarter arc about `centre` of radius `r` from angle a0 to a1
// (degrees), both ends included, in `steps` segments.
void add_arc(std::vector<glm::dvec2>& out, glm::dvec2 centre, double r, double a0, double a1, int steps) {
  for (int s = 0; s <= steps; ++s) {
    const double a = (a0 + (a1 - a0) * s / steps) * kPi / 180;
    out.push_back(centre + r * glm::dvec2(std::cos(a), std::sin(a)));
  }
}

// The profile with points added along each edge, at most `step` apart: a
// CAD export's tessellation of a long face has vertices along it, not only
// at its ends, and the thickness on the part is read at vertices.
std::vector<glm::dvec2> refined(const std::vector<glm::dvec2>& profile, double step = 0.5) {
  std::vector<glm::dvec2> out;
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const glm::dvec2 a = profile[i], b = profile[(i + 1) % profile.size()];
    const int n = std::max(1, static_cast<int>(std::ceil(glm::length(b - a) / step)));
    for (int k = 0; k < n; ++k) out.push_back(a + (b - a) * (static_cast<double>(k) / n));
  }
  return out;
}

// A tube about z, outer radius R, inner r, from z = 0 to H.
Mesh tube(double R, double r, double H, int segments) { return make_lathe(refined({{r, 0}, {R, 0}, {R, H}, {r, H}}), segments); }

Mesh sphere_shell(double R, double r) {
  return concat({make_icosphere({0, 0, 0}, R, 5), flipped(make_icosphere({0, 0, 0}, r, 5))});
}

// A sleeve whose faces both lean `draft` degrees inwards towards its top, as
// a moulded part's walls do: wall `t` across (normal to the faces), base
// inner radius r0, height H.
Mesh drafted_sleeve(double r0, double t, double H, double draft, int segments) {
  const double a = draft * kPi / 180;
  const double across = t / std::cos(a);  // horizontally
  const double in = H * std::tan(a);
  return make_lathe(refined({{r0, 0}, {r0 + across, 0}, {r0 + across - in, H}, {r0 - in, H}}), segments);
}

// A cup: outer radius R, inner r, height H, floor f thick.
Mesh cup(double R, double r, double H, double f, int segments) {
  return make_lathe(refined({{0, 0}, {R, 0}, {R, H}, {r, H}, {r, f}, {0, f}}), segments);
}

// A boss (outer radius 4, bore 2.5: a 1.5 wall, 6 high) on a plate 1.5 thick
// and 9 in radius, bored through, its root filleted with radius 0.5.
Mesh boss_on_plate(int segments) {
  std::vector<glm::dvec2> p = {{2.5, 0}, {9, 0}, {9, 1.5}};
  add_arc(p, {4.5, 2.0}, 0.5, 270, 180, 6);
  p.push_back({4, 6});
  p.push_back({2.5, 6});
  return make_lathe(refined(p), segments);
}

// A hub (tube R 4 / r 3, 6 high) with a rib 1.2 thick standing 2.5 out of it
// at mid-height, filleted (radius 0.4) where it meets the hub.
Mesh ribbed_hub(int segments) {
  std::vector<glm::dvec2> p = {{3, 0}, {4, 0}};
  add_arc(p, {4.4, 2.0 - 0.4}, 0.4, 180, 90, 5);
  p.push_back({6.5, 2.0});
  p.push_back({6.5, 3.2});
  add_arc(p, {4.4, 3.2 + 0.4}, 0.4, 270, 180, 5);
  p.push_back({4, 6});
  p.push_back({3, 6});
  return make_lathe(refined(p), segments);
}

// A straight rib 1.0 thick and 4 tall on a plate 2.0 thick and 12 wide,
// filleted (radius 0.5) at its root, 6 deep.
Mesh ribbed_plate() {
  std::vector<glm::dvec2> p = {{0, 0}, {12, 0}, {12, 2}};
  add_arc(p, {7.0, 2.5}, 0.5, 270, 180, 6);
  p.push_back({6.5, 6});
  p.push_back({5.5, 6});
  add_arc(p, {5.0, 2.5}, 0.5, 0, -90, 6);
  p.push_back({0, 2});
  return flipped(make_extrusion(p, 0, 6));  // outward: the outline runs counter-clockwise in (x, z)
}

}  // namespace

std::vector<WallPart> curved_wall_parts() {
  return {
      {"tube R 6 / r 4.5, axis z", 1.5, tube(6, 4.5, 6, 192)},
      {"tube R 10 / r 8, axis z", 2.0, tube(10, 8, 6, 256)},
      {"tube R 5 / r 3.8, turned 30/20", 1.2, rotated(tube(5, 3.8, 6, 160), 30, 20)},
      {"tube R 7 / r 6.2, turned 47/113", 0.8, rotated(tube(7, 6.2, 4, 224), 47, 113)},
      {"tube R 6 / r 3, turned 71/16", 3.0, rotated(tube(6, 3, 5, 192), 71, 16)},
      {"shell R 6 / r 4.8, turned 30/20", 1.2, rotated(sphere_shell(6, 4.8), 30, 20)},
      {"shell R 5 / r 3, turned 58/141", 2.0, rotated(sphere_shell(5, 3), 58, 141)},
      {"cup R 8 / r 6.5, floor 2, turned 30/20", 1.5, rotated(cup(8, 6.5, 8, 2, 192), 30, 20)},
      {"sleeve drafted 5°, wall 1.0, turned 23/77", 1.0, rotated(drafted_sleeve(5, 1.0, 6, 5, 192), 23, 77)},
      {"boss R 4 / bore 2.5 on a plate, filleted, turned 12/35", 1.5, rotated(boss_on_plate(192), 12, 35)},
      {"hub with a filleted rib 1.2, turned 64/9", 1.0, rotated(ribbed_hub(192), 64, 9)},
      {"straight rib 1.0 on a plate, filleted, turned 19/41", 1.0, rotated(ribbed_plate(), 19, 41)},
  };
}

}  // namespace voxd::test
