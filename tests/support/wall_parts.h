#pragma once
// Generated CAD-like parts whose walls are known, the corpus of the wall-
// thickness accuracy checks (tests/core/wall_thickness_test.cpp and
// bench/wall_accuracy): tubes of several radii and wall ratios, spherical
// shells, a cup with a floor, a drafted sleeve, a boss with a bore on a
// plate, a hub with a filleted rib and a straight filleted rib on a plate,
// walls from 0.8 to 3 mm, most turned off the grid. Closed and outward
// oriented, with vertices along their faces every 0.5 mm (as a CAD
// export's tessellation has; the thickness on the part is read at
// vertices), except the straight rib's extrusion; fillets are arcs of segments turning by less than 30° each, so
// they are smooth faces to tests/support/ray_thickness.h, not sharp edges.
#include <string>
#include <vector>

#include "voxd/mesh.h"

namespace voxd::test {

struct WallPart {
  std::string name;
  double wall = 0;  // the thinnest wall, mm: each face's distance to the face opposite it
  Mesh mesh;
};

// The parts above, for voxels of 0.05 mm (walls 16 to 60 voxels).
std::vector<WallPart> curved_wall_parts();

}  // namespace voxd::test
