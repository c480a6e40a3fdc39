// Slab-streamed voxelization (voxd/voxelize/streamed.h) and the writers that
// take its slabs (voxd/encode/slab_writer.h): the same voxels and the same
// bytes as the in-memory path, for every streamed mode and format, on real
// meshes, whatever the slab size (including grids whose z size is not a
// multiple of it).
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/encode/volume_format.h"
#include "voxd/error.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/voxelize/streamed.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using test::grid_for;
using test::part_mesh;

// The streamed slabs put back together, checking their order and grids.
BitVolume assembled(const Mesh& mesh, const Grid& grid, const VoxelizeOptions& options, std::int64_t layers) {
  BitVolume whole(grid);
  std::int64_t next = 0;
  voxelize_streamed(mesh, grid, options, layers, [&](std::int64_t k0, const BitVolume& slab) {
    EXPECT_EQ(k0, next);
    EXPECT_EQ(slab.grid().dims.x, grid.dims.x);
    EXPECT_EQ(slab.grid().dims.y, grid.dims.y);
    EXPECT_DOUBLE_EQ(slab.grid().origin.z, grid.origin.z + static_cast<double>(k0) * grid.voxel_size);
    std::memcpy(whole.slab(k0), slab.data(), slab.byte_size());
    next = k0 + slab.grid().dims.z;
  });
  EXPECT_EQ(next, grid.dims.z);
  return whole;
}

std::vector<std::uint8_t> streamed_bytes(const Mesh& mesh, const Grid& grid, const VoxelizeOptions& options,
                                         std::int64_t layers, VolumeFormat format, const EncodeOptions& encode) {
  VectorSink sink;
  BitSlabWriter writer(grid, format, encode, sink);
  voxelize_streamed(mesh, grid, options, layers, [&](std::int64_t k0, const BitVolume& slab) { writer.write(k0, slab); });
  writer.finish();
  return sink.data;
}

bool same_words(const BitVolume& a, const BitVolume& b) {
  return a.byte_size() == b.byte_size() && std::memcmp(a.data(), b.data(), a.byte_size()) == 0;
}

struct Case {
  const char* mesh;
  std::int64_t resolution, padding;
};

TEST(StreamedVoxelize, EverySlabSizeGivesTheInMemoryVoxelsInEveryMode) {
  for (const Case c : {Case{"blob.stl", 97, 1}, Case{"hex_nut.stl", 64, 0}, Case{"torus.stl", 131, 2}}) {
    const Mesh mesh = part_mesh(c.mesh);
    const Grid grid = grid_for(mesh, c.resolution, c.padding);
    for (VoxelMode mode : {VoxelMode::solid, VoxelMode::surface, VoxelMode::solid_and_surface}) {
      VoxelizeOptions options;
      options.mode = mode;
      const BitVolume expected = voxelize(mesh, grid, options);
      ASSERT_GT(expected.count(), 0u);
      for (std::int64_t layers : {std::int64_t{1}, std::int64_t{3}, std::int64_t{7}, std::int64_t{64}, grid.dims.z}) {
        SCOPED_TRACE(std::string(c.mesh) + " " + to_string(mode) + " layers " + std::to_string(layers) + " of nz " +
                     std::to_string(grid.dims.z));
        for (int threads : {1, 3}) {
          options.threads = threads;
          EXPECT_TRUE(same_words(assembled(mesh, grid, options, layers), expected));
        }
      }
    }
  }
}

TEST(StreamedVoxelize, StreamedFilesAreByteForByteTheInMemoryOnes) {
  const Mesh mesh = part_mesh("blob.stl");
  for (std::int64_t resolution : {40, 113}) {
    const Grid grid = grid_for(mesh, resolution, 1);
    VoxelizeOptions options;
    options.mode = VoxelMode::solid_and_surface;
    const BitVolume whole = voxelize(mesh, grid, options);
    struct Out {
      VolumeFormat format;
      EncodeOptions encode;
    };
    EncodeOptions bits, gzip;
    bits.raw_packing = RawPacking::bits;
    gzip.nrrd_encoding = NrrdEncoding::gzip;
    for (const Out& out : {Out{VolumeFormat::rle, {}}, Out{VolumeFormat::raw, {}}, Out{VolumeFormat::raw, bits},
                           Out{VolumeFormat::nrrd, {}}, Out{VolumeFormat::nrrd, gzip}}) {
      VectorSink expected;
      encode_volume(whole, out.format, expected, out.encode);
      for (std::int64_t layers : {1, 5, 16}) {
        SCOPED_TRACE(std::string(to_string(out.format)) + " at " + std::to_string(resolution) + ", layers " +
                     std::to_string(layers));
        EXPECT_EQ(streamed_bytes(mesh, grid, options, layers, out.format, out.encode), expected.data);
      }
    }
  }
}

// A job spread over many workers is made range by range of layers, each
// range by another process with its own thread count: the ranges' slabs put
// side by side must be the whole run's voxels, whatever the ranges' ends
// (not multiples of anything) and the threads.
TEST(StreamedVoxelize, LayerRangesSideBySideAreTheWholeRunWhateverTheirEndsAndThreads) {
  for (const Case c : {Case{"blob.stl", 97, 1}, Case{"torus.stl", 131, 2}}) {
    const Mesh mesh = part_mesh(c.mesh);
    const Grid grid = grid_for(mesh, c.resolution, c.padding);
    const std::int64_t nz = grid.dims.z;
    for (VoxelMode mode : {VoxelMode::solid, VoxelMode::surface, VoxelMode::solid_and_surface}) {
      VoxelizeOptions options;
      options.mode = mode;
      const BitVolume expected = voxelize(mesh, grid, options);
      for (const std::vector<std::int64_t>& ends :
           {std::vector<std::int64_t>{13, nz}, {1, 7, nz / 2 + 1, nz - 1, nz}, {nz / 3, 2 * nz / 3, nz}}) {
        for (const auto& [threads, slab_layers] : {std::pair{1, 16}, std::pair{3, 5}, std::pair{2, 40}}) {
          SCOPED_TRACE(std::string(c.mesh) + " " + to_string(mode) + " threads " + std::to_string(threads) +
                       " slab layers " + std::to_string(slab_layers) + " first end " + std::to_string(ends[0]));
          options.threads = threads;
          BitVolume whole(grid);
          std::int64_t begin = 0, next = 0;
          for (const std::int64_t end : ends) {
            voxelize_streamed(
                mesh, grid, options, slab_layers,
                [&](std::int64_t k0, const BitVolume& slab) {
                  EXPECT_EQ(k0, next);
                  EXPECT_LE(k0 + slab.grid().dims.z, end);
                  std::memcpy(whole.slab(k0), slab.data(), slab.byte_size());
                  next = k0 + slab.grid().dims.z;
                },
                nullptr, LayerRange{begin, end});
            EXPECT_EQ(next, end);
            begin = end;
          }
          EXPECT_TRUE(same_words(whole, expected));
        }
      }
    }
  }
  const Mesh mesh = part_mesh("torus.stl");
  const Grid grid = grid_for(mesh, 20, 0);
  for (const LayerRange off : {LayerRange{-1, 4}, LayerRange{4, 4}, LayerRange{0, grid.dims.z + 1}}) {
    try {
      voxelize_streamed(mesh, grid, {}, 4, [](std::int64_t, const BitVolume&) {}, nullptr, off);
      ADD_FAILURE() << "range " << off.begin << ".." << off.end << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      EXPECT_NE(std::string(e.what()).find("are not a part of a grid of " + std::to_string(grid.dims.z) + " layers"),
                std::string::npos)
          << e.what();
    }
  }
}

// The RLE of a job made in parts by many workers: the head, each part's
// blocks (written apart, as each worker stores its own) and the tail are
// the whole stream's bytes.
TEST(StreamedVoxelize, RleWrittenInPartsOfLayersIsTheWholeStream) {
  const Mesh mesh = part_mesh("blob.stl");
  const Grid grid = grid_for(mesh, 97, 1);
  const std::int64_t nz = grid.dims.z;
  VoxelizeOptions options;
  const std::vector<std::uint8_t> whole = streamed_bytes(mesh, grid, options, 8, VolumeFormat::rle, {});
  VectorSink joined;
  write_rle_head(grid, joined);
  std::int64_t begin = 0;
  for (const std::int64_t end : {std::int64_t{5}, nz / 2, nz}) {
    VectorSink part;
    voxelize_streamed(mesh, grid, options, 3,
                      [&](std::int64_t k0, const BitVolume& slab) { write_rle_layer_blocks(k0, slab, part); }, nullptr,
                      LayerRange{begin, end});
    joined.write(part.data.data(), part.data.size());
    begin = end;
  }
  write_rle_tail(grid, joined);
  EXPECT_EQ(joined.data, whole);
  VectorSink in_memory;
  write_rle(voxelize(mesh, grid, options), in_memory);
  EXPECT_EQ(whole, in_memory.data);
}

TEST(StreamedVoxelize, InsideTestsThatNeedTheWholeGridAreRefusedByName) {
  VoxelizeOptions vote;
  vote.inside = InsideTest::vote;
  EXPECT_FALSE(can_stream(vote));
  vote.mode = VoxelMode::surface;  // the surface has no inside test
  EXPECT_TRUE(can_stream(vote));
  VoxelizeOptions winding;
  winding.inside = InsideTest::winding;
  const Mesh box = test::make_box({0, 0, 0}, {4, 4, 4});
  try {
    voxelize_streamed(box, test::unit_grid(4, 4, 4), winding, 2, [](std::int64_t, const BitVolume&) {});
    FAIL() << "winding streamed";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    EXPECT_NE(std::string(e.what()).find("winding inside test needs the whole grid"), std::string::npos) << e.what();
  }
}

TEST(BitSlabWriter, RefusesBinvoxAndSlabsOutOfOrder) {
  const Grid grid = test::unit_grid(8, 8, 4);
  ASSERT_TRUE(streaming_refusal(VolumeFormat::binvox));
  EXPECT_NE(streaming_refusal(VolumeFormat::binvox)->find("outer axis is x"), std::string::npos);
  VectorSink sink;
  EXPECT_THROW(BitSlabWriter(grid, VolumeFormat::binvox, {}, sink), Error);
  BitSlabWriter writer(grid, VolumeFormat::rle, {}, sink);
  Grid two = grid;
  two.dims.z = 2;
  EXPECT_THROW(writer.write(2, BitVolume(two)), std::logic_error);  // layers 0-1 first
  writer.write(0, BitVolume(two));
  EXPECT_THROW(writer.finish(), std::logic_error);  // layers 2-3 missing
  writer.write(2, BitVolume(two));
  writer.finish();
  VectorSink whole;
  encode_volume(BitVolume(grid), VolumeFormat::rle, whole);
  EXPECT_EQ(sink.data, whole.data);
}

// Past 2^32 voxels (the seam where 32-bit counts and offsets wrap): a box
// whose voxel centres are known, counted and checked layer by layer as the
// slabs pass, never held whole.
TEST(StreamedVoxelize, AGridPastTwoToThe32VoxelsCountsAndFillsExactly) {
  const Grid grid = test::unit_grid(2048, 2048, 1100);
  ASSERT_GT(grid.voxel_count(), std::uint64_t{1} << 32);
  // Centres i + 1/2 inside [0.3, 2047.6] x [0.3, 2047.2] x [0.3, 1099.7]:
  // every x, y up to 2046, every z.
  const Mesh box = test::make_box({0.3, 0.3, 0.3}, {2047.6, 2047.2, 1099.7});
  const std::uint64_t expected = std::uint64_t{2048} * 2047 * 1100;
  for (VoxelMode mode : {VoxelMode::solid, VoxelMode::solid_and_surface}) {
    SCOPED_TRACE(to_string(mode));
    VoxelizeOptions options;
    options.mode = mode;
    std::uint64_t filled = 0;
    std::int64_t checked = 0;
    voxelize_streamed(box, grid, options, streamed_slab_layers(grid, std::uint64_t{32} << 20),
                      [&](std::int64_t k0, const BitVolume& slab) {
                        filled += slab.count();
                        for (std::int64_t k : {std::int64_t{0}, std::int64_t{549}, std::int64_t{1099}}) {
                          if (k < k0 || k >= k0 + slab.grid().dims.z) continue;
                          ++checked;
                          // The surface adds the voxels the box's faces touch: row 2047
                          // (face y = 2047.2) in every layer, nothing past x = 2048.
                          const std::int64_t last_row = mode == VoxelMode::solid ? 2046 : 2047;
                          for (std::int64_t j = 0; j < 2048; ++j) {
                            const std::uint64_t* row = slab.row(j, k - k0);
                            const std::uint64_t want = j <= last_row ? ~std::uint64_t{0} : 0;
                            for (std::int64_t w = 0; w < slab.row_words(); ++w)
                              if (row[w] != want) {
                                ADD_FAILURE() << "layer " << k << " row " << j << " word " << w;
                                return;
                              }
                          }
                        }
                      });
    EXPECT_EQ(checked, 3);
    if (mode == VoxelMode::solid) EXPECT_EQ(filled, expected);
    else EXPECT_EQ(filled, std::uint64_t{2048} * 2048 * 1100);  // every voxel touches the box's closed surface or is inside
  }
}

TEST(StreamedVoxelize, SlabLayersFollowTheBudget) {
  const Grid grid = test::unit_grid(8192, 8192, 8192);  // 8 MiB a layer of bits
  EXPECT_EQ(streamed_slab_layers(grid, std::uint64_t{128} << 20), 16);
  EXPECT_EQ(streamed_slab_layers(grid, 1), 1);
  EXPECT_EQ(streamed_slab_layers(test::unit_grid(64, 64, 10), std::uint64_t{1} << 30), 10);
}

}  // namespace
}  // namespace voxd
