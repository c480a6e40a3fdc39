#pragma once
// A palette reconstruction (PaletteVolume::element, voxd/voxelize/palette.h) as a
// surface: every voxel replaced by the geometry of its element
// (voxd/voxelize/palette_geometry.h), in model coordinates.
//
// Placement. voxel_scale (default 1, 1, 1) stretches the grid's space per
// axis, origin included: the palette voxelizer runs anisotropic voxels in
// a space divided by their aspect, where they are cubes, and this maps it
// back. Voxel (i, j, k) occupies
//   O + [i, i+1) * size.x  x  [j, j+1) * size.y  x  [k, k+1) * size.z,
// O = grid.origin * voxel_scale, size = grid.voxel_size * voxel_scale, and
// an element point p in [0, 1]^3 lands at O + ((i, j, k) + p) * size;
// normals follow the stretched geometry. Model coordinates are written as
// float32.
//
// Culling. A full element (a piece without half-spaces, or volume 1) is a
// cube; inside a solid part its faces would only hide each other, so a full
// voxel contributes just the faces whose 6-neighbour is not full (outside
// the grid counts as not full). Elements of zero volume contribute nothing.
// Every other element contributes its whole mesh, one closed shell per
// convex piece: where a partial element meets a full voxel, or a piece
// overlaps another of a union, the surfaces touch or overlap without being
// merged. The signed volume enclosed by the output (divergence theorem) is
// therefore the sum of the voxels' volumes whenever no element's pieces
// overlap (the built-in palettes' do not).
//
// Both writers check the volume first (one pass, which also counts the
// output), then write. Throws Error(invalid_argument) for a voxel whose
// element index is not in the palette, a non-positive or non-finite
// voxel_scale or voxel size, and Error(limit_exceeded) when the output does
// not fit its format (2^32 - 1 STL triangles, 4 GiB for a GLB).
#include <cstdint>

#include <glm/vec3.hpp>

#include "voxd/byte_sink.h"
#include "voxd/dense_volume.h"
#include "voxd/voxelize/palette.h"

namespace voxd {

// Binary STL: an 80-byte header, the triangle count, then per triangle its
// facet normal (unit, from the model-space triangle), three corners and a
// zero attribute word, all little-endian. Written slab by slab, row by row,
// in pieces of about 1 MiB: the mesh is never held whole, only each
// element's mesh once.
void write_palette_stl(const Palette& palette, const DenseVolume<std::uint8_t>& element,
                       const glm::dvec3& voxel_scale, ByteSink& sink);
inline void write_palette_stl(const Palette& palette, const DenseVolume<std::uint8_t>& element, ByteSink& sink) {
  write_palette_stl(palette, element, glm::dvec3(1.0), sink);
}

// glTF 2.0 binary (.glb), instanced: for each element that places at least
// one voxel (full ones: an exposed one, above), one mesh (non-indexed
// triangles, POSITION and NORMAL, three vertices per triangle for flat
// shading, positions pre-scaled by size so a voxel's corner (0, 0, 0) is at
// the mesh origin) and one node named after the element, drawing it once per
// voxel through EXT_mesh_gpu_instancing: its TRANSLATION accessor holds
// each voxel's minimum corner, O + (i, j, k) * size, in x-fastest
// order. The extension is listed in extensionsUsed and extensionsRequired:
// a viewer without it refuses the file instead of drawing one copy of each
// element at the origin (three.js's GLTFLoader has it; for a viewer that
// does not, the palette's STL is plain geometry). No material (viewers
// use their default). Every accessor carries min/max; buffer views are
// 4-byte aligned; the JSON chunk is padded with spaces, the BIN chunk with
// zeros. An all-empty volume gives a valid file with an empty scene and no
// BIN chunk.
//
// The BIN chunk is written element by element, each one's translations by
// one scan of the slabs that hold it, in pieces of about 1 MiB, so memory
// stays small whatever the volume; the price is a scan of the volume's bytes
// per used element.
void write_palette_glb(const Palette& palette, const DenseVolume<std::uint8_t>& element,
                       const glm::dvec3& voxel_scale, ByteSink& sink);
inline void write_palette_glb(const Palette& palette, const DenseVolume<std::uint8_t>& element, ByteSink& sink) {
  write_palette_glb(palette, element, glm::dvec3(1.0), sink);
}

}  // namespace voxd
