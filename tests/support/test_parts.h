#pragma once
// CAD-like parts made in code, each with what it measures in closed form:
// the tests' real-world meshes (a hex nut, a screw, a flanged bushing, a
// disk, a torus and an organic blob), so that a clone of the repository
// needs no mesh from outside it. Every part is closed and outward oriented;
// its volume and area are those of the polyhedron itself (not of the smooth
// shape it approximates), up to the rounding of its vertices to float.
//
// Most parts are solids of revolution (`make_lathe`): every horizontal
// section is a regular n-gon, or an n-gon ring, of circumradius r(z), whose
// area is k r^2 with k = (n/2) sin(2 pi / n). Along a profile edge r is
// linear in z, so the volume is k * sum dz (r1^2 + r1 r2 + r2^2) / 3 (by
// Green's theorem on the profile), and each edge sweeps n planar trapezoids.
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "voxd/mesh.h"

namespace voxd::test {

struct Part {
  std::string name;  // file name the tests upload it as, e.g. "hex_nut.stl"
  Mesh mesh;
  double volume = 0.0;        // of the polyhedron, closed form
  double surface_area = 0.0;  // of the polyhedron, closed form
  // The distance between a wall's two faces where the part is thinnest (a
  // sharp edge or a thread's crest is not a wall), and the diameter of the
  // largest ball that fits inside it (where walls meet, more than either).
  // Of the smooth shape the facets approximate; 0 where not known.
  double thinnest_wall = 0.0;
  double largest_ball = 0.0;
  // Holes through the part: the genus of its closed surface.
  int genus = 0;
};

// A solid of revolution about z: the closed `profile` of (r, z) points,
// counter-clockwise with r to the right and z up, r >= 0 (points with r = 0
// lie on the axis), turned through `segments` equal steps. Its volume and
// area in closed form are `lathe_volume` and `lathe_area`.
Mesh make_lathe(const std::vector<glm::dvec2>& profile, int segments);
double lathe_volume(const std::vector<glm::dvec2>& profile, int segments);
double lathe_area(const std::vector<glm::dvec2>& profile, int segments);

// A hex nut: a hexagonal prism `across_flats` wide (corners on +-y), from
// z = 0 to `height`, with a bore of diameter `bore` (a regular polygon of
// `bore_segments` sides, a multiple of 6). Chosen thinner than its ring, as
// a thin nut: the wall is the height everywhere.
Part make_hex_nut(double across_flats = 5.5, double bore = 2.5, double height = 1.2, int bore_segments = 48);

// A screw-like threaded cylinder: a round head 5.5 across and 3 high on an
// M3 shank 10 long, whose thread has the ISO basic profile (pitch 0.5,
// 60-degree flanks, crest flat P/8, root flat P/4, core 2.46 across) turned
// into 20 rings (a revolved thread: every section is round, so its volume
// and area stay in closed form).
Part make_screw(int segments = 96);

// A flanged bushing: a tube (bore 6, outside 8, 10 high) on a flange 16
// across and 1.5 thick.
Part make_flanged_bushing(int segments = 96);

// A disk 15 across and 0.2 thick, as the thinnest plate a printer makes.
Part make_disk(int segments = 96);

// A torus about z resting on z = 0: major radius 11.44, a round bar 5.66
// across (a 24-gon turned through 64 steps: 3,072 triangles), made as a
// lathe, so in closed form like the others.
Part make_torus_part();

// An organic closed shape, star-shaped about its centre (an icosphere pushed
// in and out by a few smooth waves), stretched to the box of a scanned bunny:
// 108 x 87 x 107 from (-23.89, -41.43, 5.25). Its volume and area are summed
// from its facets (`mesh_volume`), not in closed form.
Part make_blob(int level = 3);

// Every part above, in that order, by its file name.
std::vector<Part> all_parts();
// The part of that file name (e.g. "screw.stl"); throws if unknown.
Part part_named(const std::string& name);

// The mesh of the part of that file name.
inline Mesh part_mesh(const std::string& name) { return part_named(name).mesh; }

// The area of a triangle mesh, summed from its facets.
double mesh_area(const Mesh& mesh);

}  // namespace voxd::test
