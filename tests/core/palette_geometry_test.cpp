// Palette element geometry: volumes against analytic values and against
// sampling, and every mesh a closed, outward-facing surface whose enclosed
// volume (divergence theorem) is the element's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <utility>

#include <glm/geometric.hpp>

#include "voxd/error.h"
#include "voxd/voxelize/palette_geometry.h"

namespace voxd {
namespace {

HalfSpace hs(double x, double y, double z, double d) { return HalfSpace{glm::dvec3(x, y, z), d}; }

PaletteElement element(std::vector<ConvexPiece> pieces) { return PaletteElement{"test", std::move(pieces)}; }

// palette.h's PaletteElement::contains is not ours to implement; the tests
// need only this.
bool inside(const PaletteElement& e, const glm::dvec3& p) {
  return std::any_of(e.pieces.begin(), e.pieces.end(), [&](const ConvexPiece& piece) {
    return std::all_of(piece.begin(), piece.end(), [&](const HalfSpace& h) { return h.contains(p); });
  });
}

// Share of an n^3 grid of cell centres inside the element.
double sampled_volume(const PaletteElement& e, int n) {
  std::int64_t hits = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) hits += inside(e, (glm::dvec3(i, j, k) + 0.5) / static_cast<double>(n));
  return static_cast<double>(hits) / (static_cast<double>(n) * n * n);
}

glm::dvec3 corner(const ElementMesh& m, std::size_t t, int c) { return m.vertices[m.triangles[t][c]]; }

double mesh_volume(const ElementMesh& m) {
  double six_v = 0.0;
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    six_v += glm::dot(corner(m, t, 0), glm::cross(corner(m, t, 1), corner(m, t, 2)));
  return six_v / 6.0;
}

// Every directed edge appears once and its reverse once: each edge is shared
// by exactly two triangles, which walk it in opposite directions.
void expect_closed(const ElementMesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const auto& t : m.triangles) {
    for (int c = 0; c < 3; ++c) {
      ASSERT_LT(t[c], m.vertices.size());
      ++directed[{t[c], t[(c + 1) % 3]}];
    }
    const double area = glm::length(glm::cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]));
    EXPECT_GT(area, 1e-9) << "degenerate triangle";
  }
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << "edge " << edge.first << "-" << edge.second << " walked " << count << " times one way";
    const auto reverse = directed.find({edge.second, edge.first});
    EXPECT_TRUE(reverse != directed.end() && reverse->second == 1)
        << "edge " << edge.first << "-" << edge.second << " has no opposite twin";
  }
}

// Each shell (connected set of triangles) is convex, so every triangle's
// normal points away from the centroid of its shell's vertices.
void expect_outward(const ElementMesh& m) {
  std::vector<std::uint32_t> parent(m.vertices.size());
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](std::uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& t : m.triangles) {
    parent[find(t[1])] = find(t[0]);
    parent[find(t[2])] = find(t[0]);
  }
  std::map<std::uint32_t, std::pair<glm::dvec3, int>> centroid;
  for (std::uint32_t v = 0; v < m.vertices.size(); ++v) {
    auto& [sum, n] = centroid[find(v)];
    sum += m.vertices[v];
    ++n;
  }
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& [sum, n] = centroid[find(m.triangles[t][0])];
    const glm::dvec3 c = sum / static_cast<double>(n);
    const glm::dvec3 normal = glm::cross(corner(m, t, 1) - corner(m, t, 0), corner(m, t, 2) - corner(m, t, 0));
    const glm::dvec3 middle = (corner(m, t, 0) + corner(m, t, 1) + corner(m, t, 2)) / 3.0;
    EXPECT_GT(glm::dot(normal, middle - c), 0.0) << "triangle " << t << " faces inward";
  }
}

// Vertices lie in the unit voxel and in the element (on its boundary).
void expect_within(const ElementMesh& m, const PaletteElement& e) {
  for (const glm::dvec3& v : m.vertices) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(v[a], -1e-12);
      EXPECT_LE(v[a], 1 + 1e-12);
    }
    const bool in_some_piece = std::any_of(e.pieces.begin(), e.pieces.end(), [&](const ConvexPiece& piece) {
      return std::all_of(piece.begin(), piece.end(),
                         [&](const HalfSpace& h) { return glm::dot(h.normal, v) <= h.offset + 1e-9; });
    });
    EXPECT_TRUE(in_some_piece) << v.x << " " << v.y << " " << v.z;
  }
}

// The checks every element with non-overlapping pieces passes.
void expect_solid(const PaletteElement& e, double volume) {
  SCOPED_TRACE(::testing::Message() << "expected volume " << volume);
  EXPECT_NEAR(element_volume(e), volume, 1e-12);
  const ElementMesh m = element_mesh(e);
  expect_closed(m);
  expect_outward(m);
  expect_within(m, e);
  EXPECT_NEAR(mesh_volume(m), volume, 1e-12);
}

TEST(PaletteGeometry, BasicElementsHaveTheirVolumesAndClosedMeshes) {
  expect_solid(element({{}}), 1.0);
  expect_solid(element({{hs(1, 1, 0, 1)}}), 0.5);                   // wedge
  expect_solid(element({{hs(1, 1, 1, 1)}}), 1.0 / 6.0);             // corner tetrahedron
  expect_solid(element({{hs(1, 0, 1, 1), hs(0, 1, 1, 1)}}), 1.0 / 3.0);  // corner pyramid
  // Mirror images: the tetrahedron at corner (1, 1, 1), x + y + z >= 2.
  expect_solid(element({{hs(-1, -1, -1, -2)}}), 1.0 / 6.0);
}

TEST(PaletteGeometry, MeshesHaveTheExpectedFaces) {
  const ElementMesh cube = element_mesh(element({{}}));
  EXPECT_EQ(cube.vertices.size(), 8u);
  EXPECT_EQ(cube.triangles.size(), 12u);
  // Tetrahedron: 4 corners, 4 triangles; the three cube faces cut down to triangles.
  const ElementMesh tetra = element_mesh(element({{hs(1, 1, 1, 1)}}));
  EXPECT_EQ(tetra.vertices.size(), 4u);
  EXPECT_EQ(tetra.triangles.size(), 4u);
  // Wedge: a prism, 6 corners; 2 triangles + 2 squares + the slanted rectangle.
  const ElementMesh wedge = element_mesh(element({{hs(1, 1, 0, 1)}}));
  EXPECT_EQ(wedge.vertices.size(), 6u);
  EXPECT_EQ(wedge.triangles.size(), 8u);
  // Pyramid: square base and apex, 5 corners, 2 + 4 triangles.
  const ElementMesh pyramid = element_mesh(element({{hs(1, 0, 1, 1), hs(0, 1, 1, 1)}}));
  EXPECT_EQ(pyramid.vertices.size(), 5u);
  EXPECT_EQ(pyramid.triangles.size(), 6u);
}

TEST(PaletteGeometry, DisjointPiecesAreSeparateClosedShells) {
  // The pyramid's complement as complement_of expands it: {not h1} and
  // {not h2, h1}, touching along x + z = 1. 1/2 + 1/6 = 1 - 1/3.
  const PaletteElement complement = element({{hs(-1, 0, -1, -1)}, {hs(0, -1, -1, -1), hs(1, 0, 1, 1)}});
  expect_solid(complement, 2.0 / 3.0);
  const ElementMesh m = element_mesh(complement);
  // Two shells: a wedge (6 vertices) and a tetrahedron (4), not welded together.
  EXPECT_EQ(m.vertices.size(), 10u);
  // Opposite wedges: the whole voxel, as two shells.
  expect_solid(element({{hs(1, 1, 0, 1)}, {hs(-1, -1, 0, -1)}}), 1.0);
}

TEST(PaletteGeometry, OverlapsAreCountedOnceInTheVolume) {
  // Two slabs overlapping in the middle half: the whole voxel.
  const PaletteElement two = element({{hs(1, 0, 0, 0.75)}, {hs(-1, 0, 0, -0.25)}});
  EXPECT_NEAR(element_volume(two), 1.0, 1e-12);
  // The mesh keeps both shells whole: documented, it encloses 0.75 + 0.75.
  const ElementMesh m = element_mesh(two);
  expect_closed(m);
  expect_outward(m);
  EXPECT_NEAR(mesh_volume(m), 1.5, 1e-12);
  // Three half-voxel slabs along different axes: all but the far octant.
  EXPECT_NEAR(element_volume(element({{hs(1, 0, 0, 0.5)}, {hs(0, 1, 0, 0.5)}, {hs(0, 0, 1, 0.5)}})), 7.0 / 8.0, 1e-12);
  // The same piece twice is the piece.
  EXPECT_NEAR(element_volume(element({{hs(1, 1, 1, 1)}, {hs(1, 1, 1, 1)}})), 1.0 / 6.0, 1e-12);
}

TEST(PaletteGeometry, HalfSpacesThroughFacesVerticesAndOutsideLeaveNoSlivers) {
  // Through a face, from either side.
  expect_solid(element({{hs(1, 0, 0, 1)}}), 1.0);
  EXPECT_EQ(element_mesh(element({{hs(1, 0, 0, 1)}})).triangles.size(), 12u);
  EXPECT_EQ(element_mesh(element({{hs(1, 0, 0, 0)}})).triangles.size(), 0u);
  EXPECT_EQ(element_volume(element({{hs(1, 0, 0, 0)}})), 0.0);
  EXPECT_EQ(element_volume(element({{hs(-1, 0, 0, -1)}})), 0.0);
  // Touching only a corner or an edge.
  EXPECT_EQ(element_mesh(element({{hs(1, 1, 1, 0)}})).triangles.size(), 0u);
  EXPECT_EQ(element_volume(element({{hs(1, 1, 0, 0)}})), 0.0);
  // Beyond the voxel: nothing cut, or nothing left.
  expect_solid(element({{hs(1, 1, 1, 5)}}), 1.0);
  EXPECT_EQ(element_volume(element({{hs(1, 1, 1, -5)}})), 0.0);
  // Scaled normals are the same half-space.
  expect_solid(element({{hs(3, 3, 3, 3)}}), 1.0 / 6.0);
  // Zero normal: 0 <= offset, everything or nothing.
  expect_solid(element({{hs(0, 0, 0, 0)}}), 1.0);
  EXPECT_EQ(element_volume(element({{hs(0, 0, 0, -1)}})), 0.0);
  // Empty element; a piece cut away entirely next to a real one.
  EXPECT_EQ(element_volume(element({})), 0.0);
  EXPECT_TRUE(element_mesh(element({})).vertices.empty());
  expect_solid(element({{hs(1, 0, 0, -1)}, {hs(1, 1, 1, 1)}}), 1.0 / 6.0);
}

TEST(PaletteGeometry, GeneralPlanesMatchIntegration) {
  // 0.3 x + 0.7 y - 0.2 z <= 0.4: integrate the x extent over (y, z).
  const PaletteElement e = element({{hs(0.3, 0.7, -0.2, 0.4)}});
  const int n = 2000;
  double sum = 0.0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j) {
      const double y = (j + 0.5) / n, z = (k + 0.5) / n;
      sum += std::clamp((0.4 - 0.7 * y + 0.2 * z) / 0.3, 0.0, 1.0);
    }
  const double integrated = sum / (static_cast<double>(n) * n);
  expect_solid(e, element_volume(e));
  EXPECT_NEAR(element_volume(e), integrated, 1e-5);
}

TEST(PaletteGeometry, RandomPiecesAgreeWithSampling) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> count(1, 5);
  int non_empty = 0;
  for (int trial = 0; trial < 40; ++trial) {
    ConvexPiece piece;
    for (int h = count(rng); h > 0; --h) {
      const glm::dvec3 n(unit(rng), unit(rng), unit(rng));
      // Planes through a point of the voxel, so most pieces keep something.
      const glm::dvec3 through = (glm::dvec3(unit(rng), unit(rng), unit(rng)) + 1.0) / 2.0;
      piece.push_back(HalfSpace{n, glm::dot(n, through)});
    }
    const PaletteElement e = element({piece});
    SCOPED_TRACE(trial);
    const double v = element_volume(e);
    const ElementMesh m = element_mesh(e);
    EXPECT_NEAR(v, sampled_volume(e, 60), 0.02);
    EXPECT_NEAR(mesh_volume(m), v, 1e-12);
    if (v > 0) {
      ++non_empty;
      expect_closed(m);
      expect_outward(m);
      expect_within(m, e);
    } else {
      EXPECT_TRUE(m.triangles.empty());
    }
  }
  EXPECT_GT(non_empty, 20);
}

TEST(PaletteGeometry, RandomOverlappingUnionsAgreeWithSampling) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 15; ++trial) {
    std::vector<ConvexPiece> pieces;
    for (int p = 0; p < 2 + trial % 4; ++p) {
      ConvexPiece piece;
      for (int h = 0; h < 2; ++h) {
        const glm::dvec3 n(unit(rng), unit(rng), unit(rng));
        const glm::dvec3 through = (glm::dvec3(unit(rng), unit(rng), unit(rng)) + 1.0) / 2.0;
        piece.push_back(HalfSpace{n, glm::dot(n, through)});
      }
      pieces.push_back(piece);
    }
    const PaletteElement e = element(pieces);
    SCOPED_TRACE(trial);
    EXPECT_NEAR(element_volume(e), sampled_volume(e, 60), 0.02);
  }
}

TEST(PaletteGeometry, ManyDisjointPiecesAreCheapManyOverlappingOnesThrow) {
  // 64 slabs along x, touching: one intersection per pair, all flat.
  std::vector<ConvexPiece> slabs;
  for (int i = 0; i < 64; ++i) slabs.push_back({hs(-1, 0, 0, -i / 64.0), hs(1, 0, 0, (i + 1) / 64.0)});
  expect_solid(element(slabs), 1.0);
  // 20 copies of one piece: 2^20 - 1 intersections of positive volume.
  const PaletteElement copies = element(std::vector<ConvexPiece>(20, ConvexPiece{hs(1, 1, 1, 1)}));
  try {
    element_volume(copies);
    FAIL() << "expected limit_exceeded";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::limit_exceeded);
  }
  // 12 copies stay within the limit.
  EXPECT_NEAR(element_volume(element(std::vector<ConvexPiece>(12, ConvexPiece{hs(1, 1, 1, 1)}))), 1.0 / 6.0, 1e-12);
}

TEST(PaletteGeometry, NonFiniteHalfSpacesAreRejected) {
  for (const HalfSpace& h : {hs(NAN, 0, 0, 1), hs(1, INFINITY, 0, 1), hs(1, 0, 0, NAN)}) {
    try {
      element_mesh(element({{h}}));
      FAIL() << "expected invalid_argument";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    }
    EXPECT_THROW(element_volume(element({{h}})), Error);
  }
}

}  // namespace
}  // namespace voxd
