// Slab-streamed coverage (voxelize_coverage_streamed) and the writer that
// takes slabs of values (ValueSlabWriter): every slab's floats are bit for
// bit voxelize_coverage()'s, for each sampling, on CAD-like parts and an organic blob, whatever the
// slab size (including grids whose z size is not a multiple of it), and the
// files are byte for byte encode_volume()'s in every format that streams;
// a stored values RLE replays as those slabs, and its sections gathered over
// them are the whole volume's.
#include <algorithm>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "voxd/analysis/value_images.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/encode/volume_format.h"
#include "voxd/error.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/progress.h"
#include "voxd/voxelize/coverage.h"
#include "voxd/voxelize/streamed.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {


Grid grid_for(const Mesh& mesh, std::int64_t resolution) {
  GridRequest r;
  r.resolution = resolution;
  r.padding = 1;
  return resolve_grid(r, bounds(mesh));
}

bool same_floats(const DenseVolume<float>& a, const DenseVolume<float>& b) {
  return a.values().size() == b.values().size() &&
         std::memcmp(a.values().data(), b.values().data(), a.values().size() * sizeof(float)) == 0;
}

// The streamed slabs put back together, checking their order and grids.
DenseVolume<float> assembled(const Mesh& mesh, const Grid& grid, const CoverageOptions& options, std::int64_t layers) {
  DenseVolume<float> whole(grid, -1.0f);
  std::int64_t next = 0;
  voxelize_coverage_streamed(mesh, grid, options, layers, [&](std::int64_t k0, const DenseVolume<float>& slab) {
    EXPECT_EQ(k0, next);
    EXPECT_EQ(slab.grid().dims.x, grid.dims.x);
    EXPECT_EQ(slab.grid().dims.y, grid.dims.y);
    EXPECT_DOUBLE_EQ(slab.grid().origin.z, grid.origin.z + static_cast<double>(k0) * grid.voxel_size);
    std::memcpy(whole.slab(k0), slab.values().data(), slab.values().size() * sizeof(float));
    next = k0 + slab.grid().dims.z;
  });
  EXPECT_EQ(next, grid.dims.z);
  return whole;
}

TEST(StreamedCoverage, EverySlabSizeGivesTheInMemoryValuesForEachSampling) {
  struct Case {
    const char* mesh;
    std::int64_t resolution;
  };
  for (const Case c : {Case{"blob.stl", 61}, Case{"torus.stl", 47}}) {
    const Mesh mesh = test::part_mesh(c.mesh);
    const Grid grid = grid_for(mesh, c.resolution);
    for (CoverageSampling sampling : {CoverageSampling::exact, CoverageSampling::uniform, CoverageSampling::stochastic}) {
      CoverageOptions options;
      options.sampling = sampling;
      options.rays = 3;
      const DenseVolume<float> expected = voxelize_coverage(mesh, grid, options);
      ASSERT_GT(covered_voxels(expected), 100.0);
      for (std::int64_t layers : {std::int64_t{1}, std::int64_t{4}, std::int64_t{9}, grid.dims.z}) {
        for (int threads : {1, 3}) {
          SCOPED_TRACE(std::string(c.mesh) + " " + to_string(sampling) + " layers " + std::to_string(layers) +
                       " of nz " + std::to_string(grid.dims.z) + ", threads " + std::to_string(threads));
          options.threads = threads;
          EXPECT_TRUE(same_floats(assembled(mesh, grid, options, layers), expected));
        }
      }
    }
  }
}

TEST(StreamedCoverage, CoveredVoxelsOverSlabsIsTheWholeVolumesSum) {
  const Mesh mesh = test::part_mesh("blob.stl");
  const Grid grid = grid_for(mesh, 53);
  const DenseVolume<float> whole = voxelize_coverage(mesh, grid, CoverageOptions{});
  for (std::int64_t layers : {1, 6, 100}) {
    CoveredVoxels sum;
    voxelize_coverage_streamed(mesh, grid, CoverageOptions{}, layers,
                               [&](std::int64_t, const DenseVolume<float>& slab) { sum.add(slab, 2); });
    EXPECT_EQ(sum.total(), covered_voxels(whole, 1)) << layers;
  }
}

TEST(ValueSlabWriter, StreamedFilesAreByteForByteTheInMemoryOnes) {
  const Mesh mesh = test::part_mesh("hex_nut.stl");
  const Grid grid = grid_for(mesh, 45);
  const DenseVolume<float> fractions = voxelize_coverage(mesh, grid, CoverageOptions{});
  const DenseVolume<std::uint8_t> bytes = coverage_bytes(fractions);
  EncodeOptions gzip;
  gzip.nrrd_encoding = NrrdEncoding::gzip;
  gzip.content = "coverage";
  struct Out {
    VolumeFormat format;
    EncodeOptions encode;
  };
  for (bool as_bytes : {true, false}) {
    for (const Out& out : {Out{VolumeFormat::rle, {}}, Out{VolumeFormat::raw, {}}, Out{VolumeFormat::nrrd, {}},
                           Out{VolumeFormat::nrrd, gzip}}) {
      const ValueVolume whole = as_bytes ? ValueVolume(bytes) : ValueVolume(fractions);
      VectorSink expected;
      encode_volume(whole, out.format, expected, out.encode);
      for (std::int64_t layers : {1, 4, 7}) {
        SCOPED_TRACE(std::string(as_bytes ? "u8 " : "f32 ") + to_string(out.format) + ", layers " + std::to_string(layers));
        VectorSink got;
        ValueSlabWriter writer(grid, whole, out.format, out.encode, got);
        voxelize_coverage_streamed(mesh, grid, CoverageOptions{}, layers,
                                   [&](std::int64_t k0, const DenseVolume<float>& slab) {
                                     if (as_bytes)
                                       writer.write(k0, ValueVolume(coverage_bytes(slab)));
                                     else
                                       writer.write(k0, ValueVolume(slab));
                                   });
        writer.finish();
        EXPECT_EQ(got.data, expected.data);
      }
    }
  }
}

TEST(ValueSlabWriter, RefusesWhatCannotStreamAndSlabsOutOfOrderOrOfAnotherType) {
  const Grid grid = test::unit_grid(4, 4, 4);
  const ValueVolume floats = DenseVolume<float>(grid, 0.5f);
  const ValueVolume bytes = DenseVolume<std::uint8_t>(grid, 7);
  EncodeOptions quantized;
  quantized.quantize = Quantize::u8;
  VectorSink sink;
  const auto refusal = [&](const ValueVolume& type, VolumeFormat format, const EncodeOptions& options) {
    try {
      ValueSlabWriter writer(grid, type, format, options, sink);
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refusal(floats, VolumeFormat::rle, quantized).find("quantized RLE does not stream"), std::string::npos);
  EXPECT_NE(refusal(bytes, VolumeFormat::binvox, {}).find("binvox does not stream"), std::string::npos);
  EXPECT_NE(refusal(floats, VolumeFormat::binvox, {}).find("binvox holds bits or bytes"), std::string::npos);
  EXPECT_FALSE(streaming_refusal(bytes, VolumeFormat::nrrd, {}).has_value());

  ValueSlabWriter writer(grid, floats, VolumeFormat::raw, {}, sink);
  EXPECT_THROW(writer.write(1, floats), std::logic_error);  // not the first layer
  EXPECT_THROW(writer.write(0, bytes), std::logic_error);   // not floats
  EXPECT_THROW(writer.finish(), std::logic_error);          // layers missing
  writer.write(0, floats);
  writer.finish();
  EXPECT_EQ(sink.data.size(), 64 * sizeof(float));
}

TEST(ValueSlabs, AStoredRleReplaysAsItsSlabsAndItsSectionsAreTheWholeVolumes) {
  const Mesh mesh = test::part_mesh("blob.stl");
  const Grid grid = grid_for(mesh, 57);
  const DenseVolume<float> fractions = voxelize_coverage(mesh, grid, CoverageOptions{});
  const DenseVolume<std::uint8_t> bytes = coverage_bytes(fractions);
  for (bool as_bytes : {true, false}) {
    const ValueVolume whole = as_bytes ? ValueVolume(bytes) : ValueVolume(fractions);
    VectorSink rle;
    encode_volume(whole, VolumeFormat::rle, rle);
    for (std::int64_t layers : {std::int64_t{1}, std::int64_t{5}, grid.dims.z}) {
      SCOPED_TRACE(std::string(as_bytes ? "u8" : "f32") + " layers " + std::to_string(layers));
      // Re-encoded from the replayed slabs: the same stream.
      VectorSink again;
      ValueSlabWriter writer(grid, whole, VolumeFormat::rle, {}, again);
      std::vector<CoverageSectionGatherer> sections;
      for (int axis = 0; axis < 3; ++axis) sections.emplace_back(grid, axis, grid.dims[axis] / 2);
      read_rle_value_slabs(rle.data, layers, [&](std::int64_t k0, const ValueVolume& slab) {
        EXPECT_LE(grid_of(slab).dims.z, layers);
        writer.write(k0, slab);
        for (CoverageSectionGatherer& s : sections) std::visit([&](const auto& v) {
          if constexpr (!std::is_same_v<std::decay_t<decltype(v)>, DenseVolume<Rgba8>>) s.add(k0, v);
        }, slab);
      });
      writer.finish();
      EXPECT_EQ(again.data, rle.data);
      for (int axis = 0; axis < 3; ++axis) {
        const std::vector<std::uint8_t> expected =
            as_bytes ? coverage_section_png(bytes, axis, grid.dims[axis] / 2, {{"voxd:job", "j"}})
                     : coverage_section_png(fractions, axis, grid.dims[axis] / 2, {{"voxd:job", "j"}});
        EXPECT_EQ(sections[static_cast<std::size_t>(axis)].png({{"voxd:job", "j"}}), expected) << "axis " << axis;
      }
    }
  }
  // A bit stream is not values; a stream cut short says where.
  VectorSink bits;
  write_rle(BitVolume(grid), bits);
  EXPECT_THROW(read_rle_value_slabs(bits.data, 4, [](std::int64_t, const ValueVolume&) {}), Error);
  VectorSink u8;
  write_rle(bytes, u8);
  u8.data.resize(u8.data.size() / 2);
  try {
    read_rle_value_slabs(u8.data, 4, [](std::int64_t, const ValueVolume&) {});
    FAIL() << "a truncated stream was read";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::truncated_input) << e.what();
  }
  // One slab past the reader's limit is refused before it is allocated.
  ReadLimits tight;
  tight.max_volume_bytes = 100;
  EXPECT_THROW(read_rle_value_slabs(u8.data, 4, [](std::int64_t, const ValueVolume&) {}, tight), Error);
}

// A long streamed job shows steady progress and stops within a slab when
// cancelled: for the bits and for coverage, the progress seen by each slab
// grows to the slab's share of the grid, and a cancel asked for in the third
// slab's consumer is the last slab handed on.
TEST(StreamedProgress, EachSlabAdvancesTheProgressAndACancelStopsWithinTheNext) {
  const Mesh mesh = test::part_mesh("blob.stl");
  const Grid grid = grid_for(mesh, 64);
  const std::int64_t layers = 8, slabs = (grid.dims.z + layers - 1) / layers;
  ASSERT_GE(slabs, 5);
  using Run = std::function<void(JobControl&, const std::function<void(std::int64_t, std::int64_t)>&)>;
  const std::vector<std::pair<std::string, Run>> runs = {
      {"bits",
       [&](JobControl& control, const std::function<void(std::int64_t, std::int64_t)>& seen) {
         voxelize_streamed(mesh, grid, VoxelizeOptions{}, layers,
                           [&](std::int64_t k0, const BitVolume& slab) { seen(k0, slab.grid().dims.z); }, &control);
       }},
      {"coverage", [&](JobControl& control, const std::function<void(std::int64_t, std::int64_t)>& seen) {
         voxelize_coverage_streamed(mesh, grid, CoverageOptions{}, layers,
                                    [&](std::int64_t k0, const DenseVolume<float>& slab) { seen(k0, slab.grid().dims.z); },
                                    &control);
       }}};
  for (const auto& [name, run] : runs) {
    SCOPED_TRACE(name);
    JobControl control;
    std::vector<double> progress;
    run(control, [&](std::int64_t k0, std::int64_t n) {
      // The coverage reports rows as they finish; the bits report a slab
      // once handed on: at least the slabs before this one are counted.
      EXPECT_GE(control.progress() + 1e-9, static_cast<double>(k0) / static_cast<double>(grid.dims.z));
      EXPECT_LE(control.progress(), static_cast<double>(k0 + n) / static_cast<double>(grid.dims.z) + 1e-9);
      progress.push_back(control.progress());
    });
    EXPECT_EQ(static_cast<std::int64_t>(progress.size()), slabs);
    EXPECT_TRUE(std::is_sorted(progress.begin(), progress.end()));
    EXPECT_DOUBLE_EQ(control.progress(), 1.0);

    JobControl cancelled;
    std::int64_t handed_on = 0;
    try {
      run(cancelled, [&](std::int64_t, std::int64_t) {
        if (++handed_on == 3) cancelled.request_cancel();
      });
      FAIL() << "a cancelled run finished";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::cancelled);
    }
    EXPECT_EQ(handed_on, 3);
  }
}

}  // namespace
}  // namespace voxd
