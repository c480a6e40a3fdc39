#pragma once
// Palette voxelization (Cavagnino & Gribaudo 2010): every voxel takes the
// element of a palette of shapes that best represents the part of the
// object inside it, under a metric, estimated by Monte Carlo column rays.
//
// Elements. An element is a subset of the unit voxel [0, 1]^3, in voxel
// coordinates p = (x, y, z): a union of convex pieces, each the
// intersection of half-spaces n . p <= d with the unit voxel. The empty
// element has no piece; the full element is one piece with no half-space.
// A complement is stored as the union of convex pieces it expands to
// (complement_of), so the engine sees unions only.
//
// Built-in palettes (builtin_palette), each containing the previous one:
//  -  2: empty, full.
//  - 10: + the 8 corner tetrahedra (x + y + z <= 1 and its mirror images;
//        volume 1/6).
//  - 46: the four basic elements full, wedge (x + y <= 1, a half voxel cut
//        along a face diagonal), corner tetrahedron and corner pyramid (the
//        square base z = 0 under the apex (0, 0, 1): x + z <= 1, y + z <= 1;
//        volume 1/3) under the 48 mirrorings and axis swaps of the cube:
//        1 + 12 + 8 + 24 distinct elements, plus empty.
//  - 78: 46 plus the complements that are new: the 8 tetrahedra's and the
//        24 pyramids' (a wedge's complement is a wedge, empty's is full).
// The element order of each palette is fixed (empty, full, tetrahedra,
// wedges, pyramids, complements), so element indices in a result stay
// meaningful, and the names say what each element is:
//  - "tetra-x0y1z0": the tetrahedron at the voxel corner (0, 1, 0),
//    x + (1 - y) + z <= 1;
//  - "wedge-z-x1y0": the wedge along the z edge at x = 1, y = 0,
//    (1 - x) + y <= 1;
//  - "pyramid-z0-x0y1": the pyramid on the base z = 0, its apex at
//    (0, 1, 1): x + z <= 1, (1 - y) + z <= 1;
//  - "not-...": the complement.
//
// Metrics, on an estimate of the voxel's content O (the object inside it)
// against an element E, both as the voxel's sample points:
//  - nearest: similarity B = the share of points where E and O agree
//    (1 - the symmetric difference's share of the voxel).
//  - outer ("best outer box"): B = -inf if a point of O is outside E (E
//    would leave object material uncovered), else the share where they agree.
//  - inner ("best inner box"): B = -inf if a point of E is outside O (E
//    would cover empty space), else the share where they agree.
// The element with the largest B wins. Equal estimates (frequent with few
// points: a pyramid inside a wedge-shaped content can match every sample the
// wedge does) go to the element whose exact volume is closest to the
// occupancy statistic, the share of the points inside the object, then to
// the lower index. When
// every element is -inf (a custom palette without a full element under
// outer, or without an empty one under inner), the voxel takes the nearest
// element and similarity 0.
//
// Monte Carlo estimation (the paper's): per voxel column along x, `rays`
// rays t at random (y, z) inside the column, each ray's crossings with the
// mesh computed once (exact, the coverage engine's scan conversion); along a
// ray, every voxel's segment gets `points` p sample points, stratified
// (point q at x = i + (q + r_q) / p, r_q random per ray, so all voxels of a
// column share one pattern). A point is inside when the ray has crossed the
// surface an odd number of times before it. Positions are a pure function
// of (seed, column, ray): results repeat for a seed, whatever the threads.
// Shortcut (the α/β occupancy statistic): a voxel whose t * p points are
// all inside takes the full element and all outside the empty one (when the
// palette has them; the paper's "all segments inside or outside"), without
// evaluating the elements; interior runs cost one fill.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "voxd/dense_volume.h"
#include "voxd/grid.h"
#include "voxd/mesh.h"
#include "voxd/progress.h"
#include "voxd/enum_names.h"

namespace voxd {

// n . p <= d, p in voxel coordinates [0, 1]^3.
struct HalfSpace {
  glm::dvec3 normal{0.0};
  double offset = 0.0;
  bool contains(const glm::dvec3& p) const { return normal.x * p.x + normal.y * p.y + normal.z * p.z <= offset; }
  friend bool operator==(const HalfSpace&, const HalfSpace&) = default;
};

// The intersection of its half-spaces with the unit voxel.
using ConvexPiece = std::vector<HalfSpace>;

struct PaletteElement {
  std::string name;
  std::vector<ConvexPiece> pieces;  // union; none = empty; one without half-spaces = full
  bool contains(const glm::dvec3& p) const;
};

// A palette: at most kMaxPaletteElements elements (indices fit a byte).
inline constexpr std::size_t kMaxPaletteElements = 255;
// A piece may have at most this many half-spaces, a complement at most this many pieces.
inline constexpr std::size_t kMaxHalfSpaces = 16;
inline constexpr std::size_t kMaxPieces = 64;

struct Palette {
  std::vector<PaletteElement> elements;
  // Index of the element named `name`, if any.
  std::optional<std::size_t> find(std::string_view name) const;
};

// 2, 10, 46 or 78 elements (above). Throws Error(invalid_argument) otherwise.
Palette builtin_palette(int size);

// The complement of an element within the unit voxel, as a union of convex
// pieces (the complement of a piece n_1..n_k is the disjoint union over i of
// {not h_i, h_1..h_{i-1}}). Throws Error(invalid_argument) when the
// expansion would exceed kMaxPieces.
PaletteElement complement_of(const PaletteElement& element, std::string name);

// Throws Error(invalid_argument), naming the element, for an empty palette,
// more than kMaxPaletteElements elements, duplicate or empty names,
// non-finite or zero normals, too many half-spaces or pieces.
void validate(const Palette& palette);

enum class PaletteMetric { nearest, outer, inner };
inline constexpr EnumNames<PaletteMetric, 3> kPaletteMetricNames{{
    {PaletteMetric::nearest, "nearest"}, {PaletteMetric::outer, "outer"}, {PaletteMetric::inner, "inner"}}};
inline const char* to_string(PaletteMetric metric) noexcept { return name_of(kPaletteMetricNames, metric); }

struct PaletteOptions {
  Palette palette = builtin_palette(46);
  PaletteMetric metric = PaletteMetric::nearest;
  int rays = 16;                   // t: rays per voxel column, 1..256
  int points = 4;                  // p: sample points per voxel on each ray, 1..64 (t * p <= 4096)
  std::uint64_t seed = 1;
  int threads = 0;                 // 0 = all cores
};

// Per voxel: the chosen element's index into the palette, and its
// similarity B quantized to round(255 * B) (0 also for "no admissible
// element", above).
struct PaletteVolume {
  DenseVolume<std::uint8_t> element;
  DenseVolume<std::uint8_t> similarity;
};

// Throws Error(invalid_argument) for rays or points out of range and an
// invalid palette. `control` may be null.
PaletteVolume voxelize_palette(const Mesh& mesh, const Grid& grid, const PaletteOptions& options,
                               JobControl* control = nullptr);

}  // namespace voxd
