// Voxelization straight to runs (voxd/voxelize/runs.h) and the RLE written
// from them: the voxels of the dense path and its bytes, in every mode that
// makes runs, on CAD-like parts and an organic blob, with grids that cut the part, over layer ranges
// and thread counts; and the RLE of hand-made runs (rows that end full, layers
// full or empty) against the encoder of bits.
#include <atomic>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/encode/volume_format.h"
#include "voxd/error.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/run_slab.h"
#include "voxd/voxelize/runs.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::grid_for;
using test::part_mesh;

// The middle two thirds of the part: rows start and end inside it, so
// crossings fall before and past the grid.
Grid cutting_grid(const Mesh& mesh, std::int64_t resolution) {
  const Grid whole = grid_for(mesh, resolution, 0);
  GridRequest r;
  r.kind = GridRequest::Kind::explicit_grid;
  r.voxel_size = whole.voxel_size;
  r.origin = whole.origin + glm::dvec3(whole.dims / std::int64_t{6}) * whole.voxel_size;
  r.dims = whole.dims * std::int64_t{2} / std::int64_t{3};
  return resolve_grid(r, bounds(mesh));
}

// The slabs of runs put back together as bits, checking their order, grids
// and counts.
BitVolume assembled(const Mesh& mesh, const Grid& grid, const VoxelizeOptions& options, LayerRange range = {},
                    BitVolume* into = nullptr) {
  BitVolume whole = into ? BitVolume() : BitVolume(grid);
  BitVolume& out = into ? *into : whole;
  std::int64_t next = range.begin;
  voxelize_runs(
      mesh, grid, options,
      [&](std::int64_t k0, const RunSlab& slab) {
        EXPECT_EQ(k0, next);
        EXPECT_EQ(slab.grid().dims.x, grid.dims.x);
        EXPECT_EQ(slab.grid().dims.y, grid.dims.y);
        EXPECT_DOUBLE_EQ(slab.grid().origin.z, grid.origin.z + static_cast<double>(k0) * grid.voxel_size);
        const BitVolume bits = slab.to_bits();
        EXPECT_EQ(bits.count(), slab.count());
        std::memcpy(out.slab(k0), bits.data(), bits.byte_size());
        next = k0 + slab.grid().dims.z;
      },
      nullptr, range);
  EXPECT_EQ(next, range.end < 0 ? grid.dims.z : range.end);
  return whole;
}

bool same_words(const BitVolume& a, const BitVolume& b) {
  return a.byte_size() == b.byte_size() && std::memcmp(a.data(), b.data(), a.byte_size()) == 0;
}

std::vector<std::uint8_t> rle_of(const BitVolume& volume) {
  VectorSink sink;
  encode_volume(volume, VolumeFormat::rle, sink);
  return sink.data;
}

// With `prepared`, each slab's blocks are encoded by the threads that make
// the slabs (the writer's preparer) and only copied by write(): every slab
// must come to it so, or the copy went untested.
std::vector<std::uint8_t> rle_from_runs(const Mesh& mesh, const Grid& grid, const VoxelizeOptions& options,
                                        bool prepared = false) {
  VectorSink sink;
  BitSlabWriter writer(grid, VolumeFormat::rle, {}, sink);
  std::atomic<int> preparations{0};
  int slabs = 0;
  const RunSlabPreparer prepare = writer.preparer();
  voxelize_runs(
      mesh, grid, options,
      [&](std::int64_t k0, const RunSlab& slab) {
        ++slabs;
        EXPECT_EQ(slab.prepared().k0, prepared ? k0 : -1);
        EXPECT_EQ(slab.prepared().bytes.empty(), !prepared);
        writer.write(k0, slab);
      },
      nullptr, {},
      prepared ? RunSlabPreparer([&](std::int64_t k0, RunSlab& slab) {
        ++preparations;
        prepare(k0, slab);
      })
               : RunSlabPreparer());
  writer.finish();
  EXPECT_EQ(preparations.load(), prepared ? slabs : 0);
  return sink.data;
}

struct Case {
  const char* mesh;
  std::int64_t resolution, padding;
};

TEST(RunVoxelize, RunsAreTheDenseVoxelsAndTheirRleTheSameBytesInEveryMode) {
  for (const Case c : {Case{"blob.stl", 97, 1}, Case{"hex_nut.stl", 64, 0}, Case{"torus.stl", 131, 2}}) {
    const Mesh mesh = part_mesh(c.mesh);
    for (const bool cut : {false, true}) {
      const Grid grid = cut ? cutting_grid(mesh, c.resolution) : grid_for(mesh, c.resolution, c.padding);
      for (VoxelMode mode : {VoxelMode::solid, VoxelMode::surface, VoxelMode::solid_and_surface}) {
        for (int threads : {1, 3}) {
          SCOPED_TRACE(std::string(c.mesh) + (cut ? " cut " : " whole ") + to_string(mode) + " threads " +
                       std::to_string(threads));
          VoxelizeOptions options;
          options.mode = mode;
          options.threads = threads;
          const BitVolume expected = voxelize(mesh, grid, options);
          ASSERT_GT(expected.count(), 0u);
          EXPECT_TRUE(same_words(assembled(mesh, grid, options), expected));
          EXPECT_EQ(rle_from_runs(mesh, grid, options), rle_of(expected));
          EXPECT_EQ(rle_from_runs(mesh, grid, options, /*prepared=*/true), rle_of(expected));
        }
      }
    }
  }
}

TEST(RunVoxelize, LayerRangesSideBySideAreTheWholeRun) {
  const Mesh mesh = part_mesh("blob.stl");
  const Grid grid = grid_for(mesh, 97, 1);
  const std::int64_t nz = grid.dims.z;
  for (VoxelMode mode : {VoxelMode::solid, VoxelMode::solid_and_surface}) {
    VoxelizeOptions options;
    options.mode = mode;
    const BitVolume expected = voxelize(mesh, grid, options);
    for (const std::vector<std::int64_t>& ends : {std::vector<std::int64_t>{13, nz}, {1, 7, nz / 2 + 1, nz - 1, nz}}) {
      SCOPED_TRACE(std::string(to_string(mode)) + " first end " + std::to_string(ends[0]));
      BitVolume whole(grid);
      std::int64_t begin = 0;
      for (const std::int64_t end : ends) {
        assembled(mesh, grid, options, LayerRange{begin, end}, &whole);
        begin = end;
      }
      EXPECT_TRUE(same_words(whole, expected));
    }
  }
  for (const LayerRange off : {LayerRange{-1, 4}, LayerRange{4, 4}, LayerRange{0, nz + 1}}) {
    try {
      voxelize_runs(mesh, grid, {}, [](std::int64_t, const RunSlab&) {}, nullptr, off);
      ADD_FAILURE() << "range " << off.begin << ".." << off.end << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      EXPECT_NE(std::string(e.what()).find("are not a part of a grid of"), std::string::npos) << e.what();
    }
  }
}

TEST(RunVoxelize, InsideTestsThatNeedTheWholeGridAreRefusedByName) {
  const Mesh mesh = part_mesh("torus.stl");
  const Grid grid = grid_for(mesh, 16, 0);
  for (InsideTest inside : {InsideTest::vote, InsideTest::winding}) {
    VoxelizeOptions options;
    options.inside = inside;
    EXPECT_FALSE(can_make_runs(options));
    try {
      voxelize_runs(mesh, grid, options, [](std::int64_t, const RunSlab&) {});
      ADD_FAILURE() << to_string(inside) << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      EXPECT_NE(std::string(e.what()).find(to_string(inside)), std::string::npos) << e.what();
    }
  }
}

// The RLE of runs is the RLE of their bits for the patterns the encoder of
// runs treats apart: runs ending a row and starting the next (one run in
// the stream), a layer full or empty, a row of one voxel, random bits; and
// the other formats, written through the slab's bits, too.
TEST(RunSlab, RleOfRunsIsTheRleOfTheirBits) {
  std::mt19937 random(7);
  for (const glm::i64vec3 dims : {glm::i64vec3{1, 1, 1}, glm::i64vec3{1, 5, 3}, glm::i64vec3{64, 3, 4},
                                  glm::i64vec3{70, 9, 5}, glm::i64vec3{130, 4, 6}}) {
    Grid grid;
    grid.dims = dims;
    grid.voxel_size = 0.5;
    for (int pattern = 0; pattern < 6; ++pattern) {
      SCOPED_TRACE("dims " + std::to_string(dims.x) + "x" + std::to_string(dims.y) + "x" + std::to_string(dims.z) +
                   " pattern " + std::to_string(pattern));
      BitVolume bits(grid);
      for (std::int64_t k = 0; k < dims.z; ++k)
        for (std::int64_t j = 0; j < dims.y; ++j)
          for (std::int64_t i = 0; i < dims.x; ++i) {
            bool on = false;
            switch (pattern) {
              case 0: on = false; break;
              case 1: on = true; break;
              case 2: on = (k % 2 == 0); break;                        // whole layers on and off
              case 3: on = i == 0 || i == dims.x - 1; break;           // runs across row ends
              case 4: on = (random() % 3) == 0; break;
              default: on = ((i + j + k) % 5) < 2 && k != 1; break;  // and an empty layer
            }
            bits.set(i, j, k, on);
          }
      const RunSlab runs = RunSlab::from_bits(bits);
      EXPECT_EQ(runs.count(), bits.count());
      EXPECT_TRUE(same_words(runs.to_bits(), bits));
      for (VolumeFormat format : {VolumeFormat::rle, VolumeFormat::raw, VolumeFormat::nrrd}) {
        VectorSink from_runs, from_bits;
        BitSlabWriter a(grid, format, {}, from_runs), b(grid, format, {}, from_bits);
        a.write(0, runs);
        b.write(0, bits);
        a.finish();
        b.finish();
        EXPECT_EQ(from_runs.data, from_bits.data) << to_string(format);
      }
      VectorSink blocks_of_runs, blocks_of_bits;
      write_rle_layer_blocks(0, runs, blocks_of_runs);
      write_rle_layer_blocks(0, bits, blocks_of_bits);
      EXPECT_EQ(blocks_of_runs.data, blocks_of_bits.data);
    }
  }
}

// Blocks prepared where a slab was made are what the writer copies, only
// for the layer they were made at and the rows they were made of: a slab
// handed on at another layer, cut short, grown or reset is encoded afresh.
TEST(RunSlab, PreparedBlocksAreCopiedOnlyForTheLayerAndRowsTheyWereMadeOf) {
  Grid grid;
  grid.dims = {70, 4, 3};
  grid.voxel_size = 0.5;
  BitVolume bits(grid);
  for (std::int64_t k = 0; k < 3; ++k)
    for (std::int64_t j = 0; j < 4; ++j)
      for (std::int64_t i = 0; i < 70; ++i) bits.set(i, j, k, (i * 7 + j * 3 + k) % 5 < 2);
  const auto blocks = [](std::int64_t k0, const auto& slab) {
    VectorSink sink;
    write_rle_layer_blocks(k0, slab, sink);
    return sink.data;
  };
  RunSlab runs = RunSlab::from_bits(bits);
  EXPECT_EQ(runs.prepared().k0, -1);
  prepare_rle_layer_blocks(5, runs);
  ASSERT_EQ(runs.prepared().k0, 5);
  EXPECT_EQ(blocks(5, runs), blocks(5, bits));
  // The copy is what is written: bytes planted there come out.
  runs.prepared().bytes = {1, 2, 3};
  EXPECT_EQ(blocks(5, runs), (std::vector<std::uint8_t>{1, 2, 3}));
  // At another layer the slab is encoded, not copied.
  EXPECT_EQ(blocks(6, runs), blocks(6, bits));
  // Cut to its first two layers: dropped.
  prepare_rle_layer_blocks(5, runs);
  runs.set_layers(2);
  EXPECT_EQ(runs.prepared().k0, -1);
  // Grown by more rows: dropped.
  RunSlab two = RunSlab::from_bits(bits);
  prepare_rle_layer_blocks(0, two);
  two.append_rows(RunSlab::from_bits(bits));
  EXPECT_EQ(two.prepared().k0, -1);
  // Reset for the next slab: dropped, bytes and all.
  prepare_rle_layer_blocks(0, runs);
  runs.reset(grid);
  EXPECT_EQ(runs.prepared().k0, -1);
  EXPECT_TRUE(runs.prepared().bytes.empty());
  // Only an RLE writer prepares; the formats written from bits do not.
  VectorSink sink;
  EXPECT_TRUE(static_cast<bool>(BitSlabWriter(grid, VolumeFormat::rle, {}, sink).preparer()));
  VectorSink raw_sink;
  EXPECT_FALSE(static_cast<bool>(BitSlabWriter(grid, VolumeFormat::raw, {}, raw_sink).preparer()));
}

}  // namespace
}  // namespace voxd
