// A stored RLE result replayed slab by slab (voxd/encode/rle_slabs.h) and the
// analyses that take slabs (mass properties, radiography, parts and voids,
// sections, shaded previews): on CAD-like parts and an organic blob,
// whatever the slab size (including grids whose z size is not a multiple of
// it), the slabs are the stored voxels and every streamed analysis is
// exactly its in-memory counterpart.
#include <algorithm>
#include <cstring>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "support/test_parts.h"
#include "voxd/analysis/analysis_images.h"
#include "voxd/analysis/components.h"
#include "voxd/analysis/mass_properties.h"
#include "voxd/analysis/preview.h"
#include "voxd/analysis/radiography.h"
#include "voxd/analysis/section.h"
#include "voxd/byte_source.h"
#include "voxd/encode/rle_slabs.h"
#include "voxd/encode/slab_writer.h"
#include "voxd/encode/volume_format.h"
#include "voxd/error.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

struct Stored {
  BitVolume volume;
  std::vector<std::uint8_t> rle;
};

Stored stored(const std::string& name, std::int64_t resolution) {
  const Mesh mesh = test::part_mesh(name);
  GridRequest r;
  r.resolution = resolution;
  r.padding = 1;
  Stored s{voxelize(mesh, resolve_grid(r, bounds(mesh)), VoxelizeOptions{}), {}};
  VectorSink sink;
  write_rle(s.volume, sink);
  s.rle = std::move(sink.data);
  return s;
}

// Each part once, at a resolution whose nz is prime-ish against the
// slab sizes below.
const std::vector<Stored>& cases() {
  static const std::vector<Stored> all = [] {
    std::vector<Stored> v;
    v.push_back(stored("blob.stl", 83));
    v.push_back(stored("hex_nut.stl", 70));
    v.push_back(stored("torus.stl", 101));
    return v;
  }();
  return all;
}

std::vector<std::int64_t> slab_sizes(const Grid& g) { return {1, 2, 7, g.dims.z - 1, g.dims.z}; }

bool same_words(const BitVolume& a, const BitVolume& b) {
  return a.byte_size() == b.byte_size() && std::memcmp(a.data(), b.data(), a.byte_size()) == 0;
}

TEST(RleSlabs, ReplayedSlabsAreTheStoredVoxelsInOrder) {
  for (const Stored& s : cases()) {
    const Grid& g = s.volume.grid();
    EXPECT_EQ(read_rle_bit_grid(s.rle).dims, g.dims);
    for (std::int64_t layers : slab_sizes(g)) {
      SCOPED_TRACE("layers " + std::to_string(layers) + " of nz " + std::to_string(g.dims.z));
      BitVolume whole(g);
      std::int64_t next = 0;
      read_rle_bit_slabs(s.rle, layers, [&](std::int64_t k0, const BitVolume& slab) {
        EXPECT_EQ(k0, next);
        EXPECT_LE(slab.grid().dims.z, layers);
        EXPECT_DOUBLE_EQ(slab.grid().origin.z, g.origin.z + static_cast<double>(k0) * g.voxel_size);
        std::memcpy(whole.slab(k0), slab.data(), slab.byte_size());
        next = k0 + slab.grid().dims.z;
      });
      EXPECT_EQ(next, g.dims.z);
      EXPECT_TRUE(same_words(whole, s.volume));
    }
  }
}

TEST(RleSlabs, EveryStreamedFormatReencodedFromTheRleIsTheInMemoryBytes) {
  const Stored& s = cases()[0];
  struct Format {
    VolumeFormat format;
    EncodeOptions options;
  };
  std::vector<Format> formats(4);
  formats[0].format = VolumeFormat::raw;
  formats[1].format = VolumeFormat::raw;
  formats[1].options.raw_packing = RawPacking::bits;
  formats[2].format = VolumeFormat::nrrd;
  formats[3].format = VolumeFormat::nrrd;
  formats[3].options.nrrd_encoding = NrrdEncoding::gzip;
  for (const Format& f : formats) {
    VectorSink expected;
    encode_volume(s.volume, f.format, expected, f.options);
    VectorSink streamed;
    BitSlabWriter writer(s.volume.grid(), f.format, f.options, streamed);
    read_rle_bit_slabs(s.rle, 5, [&](std::int64_t k0, const BitVolume& slab) { writer.write(k0, slab); });
    writer.finish();
    EXPECT_EQ(streamed.data, expected.data) << to_string(f.format);
  }
}

TEST(RleSlabs, ABrokenStreamStopsAtTheBadBlockWithItsOffset) {
  const Stored& s = cases()[1];
  std::vector<std::uint8_t> cut(s.rle.begin(), s.rle.begin() + static_cast<std::ptrdiff_t>(s.rle.size() / 2));
  std::int64_t layers_seen = 0;
  try {
    read_rle_bit_slabs(cut, 1, [&](std::int64_t, const BitVolume& slab) { layers_seen += slab.grid().dims.z; });
    FAIL() << "a stream cut in half was read to its end";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::truncated_input);
    EXPECT_NE(std::string(e.what()).find("byte"), std::string::npos) << e.what();
  }
  EXPECT_GT(layers_seen, 0);
  EXPECT_LT(layers_seen, s.volume.grid().dims.z);

  std::vector<std::uint8_t> padded = s.rle;
  padded.push_back(0);
  EXPECT_THROW(read_rle_bit_slabs(padded, 4, [](std::int64_t, const BitVolume&) {}), Error);
}

// The bytes a few at a time, as a store's chunks arrive (a source that is
// not in memory): the slab reader's buffered path.
class Trickle final : public ByteSource {
 public:
  Trickle(std::span<const std::uint8_t> data, std::size_t step) : data_(data), step_(step) {}
  std::size_t read(std::uint8_t* out, std::size_t size) override {
    const std::size_t n = std::min({size, step_, data_.size() - at_});
    std::memcpy(out, data_.data() + at_, n);
    at_ += n;
    return n;
  }

 private:
  std::span<const std::uint8_t> data_;
  std::size_t step_, at_ = 0;
};

// Issue #37, finding 7: a stored result is replayed from a source read front
// to back, never whole: the same slabs whatever the reads' sizes, and the
// same errors where the stream is broken.
TEST(RleSlabs, ASourceReadAPieceAtATimeGivesTheSameSlabsAndErrors) {
  for (const Stored& s : cases()) {
    for (std::size_t step : {std::size_t{1}, std::size_t{13}, std::size_t{4096}, s.rle.size()}) {
      SCOPED_TRACE("reads of " + std::to_string(step));
      Trickle header(s.rle, step);
      EXPECT_EQ(read_rle_bit_grid(header).dims, s.volume.grid().dims);
      BitVolume whole(s.volume.grid());
      Trickle source(s.rle, step);
      read_rle_bit_slabs(source, 3, [&](std::int64_t k0, const BitVolume& slab) {
        std::memcpy(whole.slab(k0), slab.data(), slab.byte_size());
      });
      EXPECT_TRUE(same_words(whole, s.volume));
    }
  }
  const Stored& s = cases()[1];
  auto error_of = [](auto&& input) {
    try {
      read_rle_bit_slabs(input, 2, [](std::int64_t, const BitVolume&) {});
    } catch (const Error& e) {
      return std::make_pair(e.code(), std::string(e.what()));
    }
    return std::make_pair(ErrorCode::io_error, std::string("no error"));
  };
  const std::vector<std::uint8_t> cut(s.rle.begin(), s.rle.begin() + static_cast<std::ptrdiff_t>(s.rle.size() / 2));
  Trickle cut_source(cut, 7);
  const auto cut_error = error_of(cut_source);
  EXPECT_EQ(cut_error, error_of(std::span<const std::uint8_t>(cut)));
  EXPECT_EQ(cut_error.first, ErrorCode::truncated_input);
  std::vector<std::uint8_t> padded = s.rle;
  padded.push_back(0);
  Trickle padded_source(padded, 7);
  const auto padded_error = error_of(padded_source);
  EXPECT_EQ(padded_error.first, ErrorCode::malformed_input);
  EXPECT_NE(padded_error.second.find("unexpected bytes after the end block"), std::string::npos) << padded_error.second;
}

// The runs of a stored result (read_rle_run_slabs): the stored voxels, in
// order, whatever the slab size and the source's reads, and the same errors
// as the bit slabs where the stream is broken.
TEST(RleSlabs, RunSlabsAreTheStoredVoxelsForAnySlabsAndReads) {
  for (const Stored& s : cases()) {
    for (std::int64_t layers : slab_sizes(s.volume.grid())) {
      for (std::size_t step : {std::size_t{5}, s.rle.size()}) {
        SCOPED_TRACE("layers " + std::to_string(layers) + ", reads of " + std::to_string(step));
        BitVolume whole(s.volume.grid());
        std::int64_t next = 0;
        Trickle source(s.rle, step);
        read_rle_run_slabs(source, layers, [&](std::int64_t k0, const RunSlab& slab) {
          EXPECT_EQ(k0, next);
          EXPECT_LE(slab.grid().dims.z, layers);
          next = k0 + slab.grid().dims.z;
          const BitVolume bits = slab.to_bits();
          std::memcpy(whole.slab(k0), bits.data(), bits.byte_size());
        });
        EXPECT_EQ(next, s.volume.grid().dims.z);
        EXPECT_TRUE(same_words(whole, s.volume));
      }
    }
  }
  const Stored& s = cases()[1];
  auto error_of = [](std::span<const std::uint8_t> input, bool runs) {
    try {
      if (runs) read_rle_run_slabs(input, 2, [](std::int64_t, const RunSlab&) {});
      else read_rle_bit_slabs(input, 2, [](std::int64_t, const BitVolume&) {});
    } catch (const Error& e) {
      return std::make_pair(e.code(), std::string(e.what()));
    }
    return std::make_pair(ErrorCode::io_error, std::string("no error"));
  };
  const std::vector<std::uint8_t> cut(s.rle.begin(), s.rle.begin() + static_cast<std::ptrdiff_t>(s.rle.size() / 2));
  EXPECT_EQ(error_of(cut, true), error_of(cut, false));
  EXPECT_EQ(error_of(cut, true).first, ErrorCode::truncated_input);
  std::vector<std::uint8_t> padded = s.rle;
  padded.push_back(0);
  EXPECT_EQ(error_of(padded, true), error_of(padded, false));
}

// What a run reader handed on, call by call (each slab's first layer, its
// layers and every row's runs), and the error it stopped with.
struct RunCalls {
  std::vector<std::vector<std::uint32_t>> calls;
  std::optional<std::pair<ErrorCode, std::string>> error;
  bool operator==(const RunCalls&) const = default;
};

template <class Input>
RunCalls run_calls(Input&& input, std::int64_t layers, int threads) {
  RunCalls out;
  try {
    read_rle_run_slabs(
        input, layers,
        [&](std::int64_t k0, const RunSlab& slab) {
          std::vector<std::uint32_t> call{static_cast<std::uint32_t>(k0), static_cast<std::uint32_t>(slab.grid().dims.z)};
          for (std::int64_t k = 0; k < slab.grid().dims.z; ++k)
            for (std::int64_t j = 0; j < slab.grid().dims.y; ++j) {
              const auto runs = slab.row(j, k);
              call.push_back(static_cast<std::uint32_t>(runs.size()));
              call.insert(call.end(), runs.begin(), runs.end());
            }
          out.calls.push_back(std::move(call));
        },
        {}, threads);
  } catch (const Error& e) {
    out.error = std::make_pair(e.code(), std::string(e.what()));
  }
  return out;
}

// Random runs of 1 to `longest` voxels, filled and empty in turn.
BitVolume random_runs(const glm::i64vec3& dims, std::uint64_t longest, unsigned seed) {
  Grid g;
  g.dims = dims;
  BitVolume v(g);
  std::mt19937_64 rng(seed);
  const std::uint64_t total = static_cast<std::uint64_t>(dims.x * dims.y * dims.z);
  bool filled = rng() % 2 == 0;
  for (std::uint64_t at = 0; at < total; filled = !filled) {
    const std::uint64_t n = std::min(total - at, 1 + rng() % longest);
    if (filled)
      for (std::uint64_t u = at; u < at + n; ++u) {
        const auto i = static_cast<std::int64_t>(u % static_cast<std::uint64_t>(dims.x));
        const auto r = static_cast<std::int64_t>(u / static_cast<std::uint64_t>(dims.x));
        v.set(i, r % dims.y, r / dims.y, true);
      }
    at += n;
  }
  return v;
}

// Read on several threads, layers are decoded apart in batches and joined
// in order: the same slabs, the same calls and the same error as on one,
// from memory and from a source read a few bytes at a time (whose buffer
// moves on under the batch). Two grids beside the parts fill more than one
// batch: one by its rows (65536 a layer), one by its payload (about 1.7 MB
// a layer: two layers a batch, and one alone).
TEST(RleSlabs, RunSlabsAreTheSameOnAnyThreads) {
  std::vector<Stored> large;
  for (auto [dims, longest] : {std::pair{glm::i64vec3{6, 65536, 37}, std::uint64_t{40}},
                               std::pair{glm::i64vec3{4096, 1024, 5}, std::uint64_t{4}}}) {
    Stored s{random_runs(dims, longest, static_cast<unsigned>(dims.x)), {}};
    VectorSink sink;
    write_rle(s.volume, sink);
    s.rle = std::move(sink.data);
    large.push_back(std::move(s));
  }
  std::vector<const Stored*> all;
  for (const Stored& s : cases()) all.push_back(&s);
  for (const Stored& s : large) all.push_back(&s);
  std::size_t index = 0;
  for (const Stored* stored_case : all) {
    const Stored& s = *stored_case;
    SCOPED_TRACE("case " + std::to_string(index++));
    const std::int64_t nz = s.volume.grid().dims.z;
    const RunCalls one = run_calls(std::span<const std::uint8_t>(s.rle), 7, 1);
    ASSERT_FALSE(one.error) << one.error->second;
    ASSERT_EQ(one.calls.size(), static_cast<std::size_t>((nz + 6) / 7));
    for (int threads : {2, 3, 8}) {
      SCOPED_TRACE("threads " + std::to_string(threads));
      EXPECT_TRUE(run_calls(std::span<const std::uint8_t>(s.rle), 7, threads) == one);
      Trickle source(s.rle, 4093);
      EXPECT_TRUE(run_calls(source, 7, threads) == one);
    }
    // A stream broken here and there: cut short, or a byte changed (a run,
    // a block's head, its length). Each thread count stops where one thread
    // does, after the same slabs, with the same message.
    std::mt19937 rng(static_cast<unsigned>(s.rle.size()));
    for (int broken = 0; broken < (s.rle.size() < 100000 ? 24 : 6); ++broken) {
      std::vector<std::uint8_t> bad = s.rle;
      const std::size_t at = 40 + rng() % (bad.size() - 40);
      if (broken % 3 == 0)
        bad.resize(at);
      else
        bad[at] = static_cast<std::uint8_t>(broken % 3 == 1 ? bad[at] ^ 0x41 : 0x53);
      SCOPED_TRACE("broken at byte " + std::to_string(at));
      const RunCalls expected = run_calls(std::span<const std::uint8_t>(bad), 2, 1);
      Trickle one_source(bad, 4093);
      ASSERT_TRUE(run_calls(one_source, 2, 1) == expected);
      for (int threads : {2, 8}) {
        EXPECT_TRUE(run_calls(std::span<const std::uint8_t>(bad), 2, threads) == expected) << threads << " threads";
        Trickle source(bad, 4093);
        EXPECT_TRUE(run_calls(source, 2, threads) == expected) << threads << " threads, trickled";
      }
    }
  }
}

// A slab of runs ends early once it holds kRunSlabRuns runs, so memory is
// bounded by the runs however many layers are asked for: grids striped
// along x (a run every other voxel) over the first 8, 7 or 5 words of each
// row, 16384 runs a word column a layer, whose parts (the planes of odd x)
// are found across the cut. On more threads the layers are decoded in
// batches, whose ends need not fall where a slab fills (at layer 64, 74 or
// 103): it ends at the same layer all the same.
TEST(RleSlabs, ARunSlabEndsOnceItHoldsEnoughRuns) {
  Grid g;
  g.dims = {512, 512, 110};
  for (const std::int64_t words : {8, 7, 5}) {
    BitVolume striped(g);
    for (std::int64_t k = 0; k < g.dims.z; ++k)
      for (std::int64_t j = 0; j < g.dims.y; ++j) {
        std::uint64_t* row = striped.row(j, k);
        for (std::int64_t w = 0; w < words; ++w) row[w] = 0xAAAAAAAAAAAAAAAAu;  // odd x filled
      }
    VectorSink rle;
    write_rle(striped, rle);
    const std::int64_t layer_runs = 512 * 32 * words;
    const auto full = static_cast<std::int64_t>((kRunSlabRuns + layer_runs - 1) / layer_runs);  // layers of the first slab
    for (const int threads : {1, 2, 3}) {
      SCOPED_TRACE(std::to_string(words) + " words, " + std::to_string(threads) + " threads");
      std::vector<std::pair<std::int64_t, std::int64_t>> slabs;
      ComponentLabeller labeller(g, 2);
      read_rle_run_slabs(
          rle.data, g.dims.z,
          [&](std::int64_t k0, const RunSlab& slab) {
            slabs.emplace_back(k0, slab.grid().dims.z);
            EXPECT_EQ(slab.count(), static_cast<std::uint64_t>(slab.grid().dims.z * layer_runs));
            labeller.add(k0, slab);
          },
          {}, threads);
      ASSERT_EQ(slabs.size(), 2u);
      EXPECT_EQ(slabs[0], std::make_pair(std::int64_t{0}, full));
      EXPECT_EQ(slabs[1], std::make_pair(full, g.dims.z - full));
      // Each plane of odd x is a part; the planes between touch the border.
      const ComponentReport r = labeller.finish();
      ASSERT_EQ(r.parts.size(), static_cast<std::size_t>(32 * words));
      for (std::size_t p = 0; p < r.parts.size(); ++p) {
        EXPECT_EQ(r.parts[p].voxels, std::uint64_t{512 * 110});
        EXPECT_EQ(r.parts[p].bbox_min, glm::i64vec3(2 * p + 1, 0, 0));
        EXPECT_EQ(r.parts[p].bbox_max, glm::i64vec3(2 * p + 1, 511, 109));
      }
      EXPECT_TRUE(r.voids.empty());
    }
  }
  // Rows bound a slab too (each has a start): a grid of 4096 x 4096 rows
  // one voxel long comes in slabs of kRunSlabRuns rows, runs or none.
  Grid rows_grid;
  rows_grid.dims = {1, 4096, 4096};
  BitVolume one_voxel_rows(rows_grid);
  one_voxel_rows.set(0, 5, 4000, true);
  VectorSink rows_rle;
  write_rle(one_voxel_rows, rows_rle);
  std::vector<std::int64_t> layers;
  std::uint64_t filled = 0;
  read_rle_run_slabs(rows_rle.data, rows_grid.dims.z, [&](std::int64_t, const RunSlab& slab) {
    layers.push_back(slab.grid().dims.z);
    filled += slab.count();
  });
  const auto most = static_cast<std::int64_t>(kRunSlabRuns / 4096);
  EXPECT_EQ(layers, (std::vector<std::int64_t>{most, 4096 - most}));
  EXPECT_EQ(filled, 1u);
}

TEST(SlabAnalyses, MassPropertiesAreExactlyTheInMemoryOnesForAnySlabsAndThreads) {
  for (const Stored& s : cases()) {
    const MassProperties expected = voxel_mass_properties(s.volume, 1);
    ASSERT_GT(expected.volume, 0.0);
    for (std::int64_t layers : slab_sizes(s.volume.grid())) {
      for (int threads : {1, 3}) {
        VoxelMassAccumulator sums(s.volume.grid()), from_runs(s.volume.grid());
        read_rle_bit_slabs(s.rle, layers, [&](std::int64_t k0, const BitVolume& slab) { sums.add(k0, slab, threads); });
        read_rle_run_slabs(s.rle, layers, [&](std::int64_t k0, const RunSlab& slab) { from_runs.add(k0, slab, threads); });
        for (const MassProperties& got : {sums.result(), from_runs.result()}) {
          EXPECT_EQ(got.volume, expected.volume);
          for (int a = 0; a < 3; ++a) {
            EXPECT_EQ(got.centroid[a], expected.centroid[a]);
            EXPECT_EQ(got.bbox.min[a], expected.bbox.min[a]);
            EXPECT_EQ(got.bbox.max[a], expected.bbox.max[a]);
            for (int b = 0; b < 3; ++b) EXPECT_EQ(got.inertia[a][b], expected.inertia[a][b]);
          }
        }
      }
    }
  }
}

TEST(SlabAnalyses, MassPropertiesOfABoxAreItsAnalyticOnes) {
  // An a x b x c block of voxels: volume abc h^3, Ixx = V (b^2 + c^2) h^2 / 12.
  Grid g;
  g.dims = {40, 30, 50};
  g.voxel_size = 0.5;
  g.origin = {1.0, -2.0, 3.0};
  BitVolume v(g);
  const std::int64_t a = 17, b = 9, c = 23;  // from voxel (5, 7, 11)
  for (std::int64_t k = 11; k < 11 + c; ++k)
    for (std::int64_t j = 7; j < 7 + b; ++j)
      for (std::int64_t i = 5; i < 5 + a; ++i) v.set(i, j, k, true);
  const double h = g.voxel_size;
  const double volume = static_cast<double>(a * b * c) * h * h * h;
  const MassProperties p = voxel_mass_properties(v);
  EXPECT_DOUBLE_EQ(p.volume, volume);
  EXPECT_DOUBLE_EQ(p.centroid.x, 1.0 + (5 + a / 2.0) * h);
  EXPECT_DOUBLE_EQ(p.centroid.y, -2.0 + (7 + b / 2.0) * h);
  EXPECT_DOUBLE_EQ(p.centroid.z, 3.0 + (11 + c / 2.0) * h);
  EXPECT_NEAR(p.inertia[0][0], volume * (b * b + c * c) * h * h / 12.0, 1e-9 * p.inertia[0][0]);
  EXPECT_NEAR(p.inertia[1][1], volume * (a * a + c * c) * h * h / 12.0, 1e-9 * p.inertia[1][1]);
  EXPECT_NEAR(p.inertia[2][2], volume * (a * a + b * b) * h * h / 12.0, 1e-9 * p.inertia[2][2]);
  EXPECT_EQ(p.inertia[0][1], 0.0);
  EXPECT_EQ(p.inertia[1][2], 0.0);
  EXPECT_EQ(p.inertia[0][2], 0.0);
}

TEST(SlabAnalyses, RadiographyAlongEachAxisIsExactlyTheInMemoryOne) {
  for (const Stored& s : cases()) {
    for (int axis = 0; axis < 3; ++axis) {
      const ThicknessImage expected = radiography(s.volume, axis);
      for (std::int64_t layers : slab_sizes(s.volume.grid())) {
        SCOPED_TRACE("axis " + std::to_string(axis) + " layers " + std::to_string(layers));
        RadiographyAccumulator image(s.volume.grid(), axis);
        read_rle_bit_slabs(s.rle, layers, [&](std::int64_t k0, const BitVolume& slab) { image.add(k0, slab, 2); });
        RadiographyAccumulator from_runs(s.volume.grid(), axis);
        read_rle_run_slabs(s.rle, layers, [&](std::int64_t k0, const RunSlab& slab) { from_runs.add(k0, slab, 2); });
        for (const ThicknessImage& got : {image.take(), from_runs.take()}) {
          EXPECT_EQ(got.width, expected.width);
          EXPECT_EQ(got.height, expected.height);
          EXPECT_EQ(got.min, expected.min);
          EXPECT_EQ(got.max, expected.max);
          EXPECT_EQ(got.total, expected.total);
        }
      }
    }
  }
}

// Random voxels filling the grid to its faces (runs open at the last layer,
// single voxels, each slab size's seams), of `density`; its RLE alongside.
Stored random_volume(double density, std::uint64_t seed) {
  std::uint64_t state = seed;
  const auto next = [&] {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return state;
  };
  Grid g;
  g.dims = {37 + static_cast<std::int64_t>(density * 40), 29, 23};
  g.voxel_size = 0.5;
  Stored s{BitVolume(g), {}};
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i)
        if (static_cast<double>(next() % 1000) < density * 1000) s.volume.set(i, j, k, true);
  VectorSink sink;
  write_rle(s.volume, sink);
  s.rle = std::move(sink.data);
  return s;
}

// Against each ray walked voxel by voxel: the shortest and longest runs and
// the filled voxels, for any slabs, as bits and as runs.
TEST(SlabAnalyses, RadiographyOfRandomVolumesIsEachRayWalkedVoxelByVoxel) {
  for (const double density : {0.2, 0.5, 0.85}) {
    const Stored s = random_volume(density, 0x51ed2701f3a5c9b1u);
    const glm::i64vec3 d = s.volume.grid().dims;
    for (int axis = 0; axis < 3; ++axis) {
      // Pixel (c, r): the other two axes in x, y, z order.
      const int ca = axis == 0 ? 1 : 0, ra = axis == 2 ? 1 : 2;
      ThicknessImage walked;
      walked.width = static_cast<int>(d[ca]);
      walked.height = static_cast<int>(d[ra]);
      for (std::int64_t r = 0; r < d[ra]; ++r)
        for (std::int64_t c = 0; c < d[ca]; ++c) {
          std::uint32_t lo = 0, hi = 0, total = 0, run = 0;
          for (std::int64_t t = 0; t <= d[axis]; ++t) {
            std::int64_t ijk[3];
            ijk[axis] = t;
            ijk[ca] = c;
            ijk[ra] = r;
            if (t < d[axis] && s.volume.get(ijk[0], ijk[1], ijk[2])) {
              ++run;
              continue;
            }
            if (run > 0) {
              lo = lo == 0 ? run : std::min(lo, run);
              hi = std::max(hi, run);
              total += run;
            }
            run = 0;
          }
          walked.min.push_back(lo);
          walked.max.push_back(hi);
          walked.total.push_back(total);
        }
      for (std::int64_t layers : {std::int64_t{1}, std::int64_t{2}, std::int64_t{5}, d.z}) {
        SCOPED_TRACE("density " + std::to_string(density) + " axis " + std::to_string(axis) + " layers " +
                     std::to_string(layers));
        RadiographyAccumulator from_bits(s.volume.grid(), axis), from_runs(s.volume.grid(), axis);
        read_rle_bit_slabs(s.rle, layers, [&](std::int64_t k0, const BitVolume& slab) { from_bits.add(k0, slab, 2); });
        read_rle_run_slabs(s.rle, layers, [&](std::int64_t k0, const RunSlab& slab) { from_runs.add(k0, slab, 2); });
        for (const ThicknessImage& got : {from_bits.take(), from_runs.take(), radiography(s.volume, axis, 2)}) {
          EXPECT_EQ(got.width, walked.width);
          EXPECT_EQ(got.height, walked.height);
          EXPECT_EQ(got.min, walked.min);
          EXPECT_EQ(got.max, walked.max);
          EXPECT_EQ(got.total, walked.total);
        }
      }
    }
  }
}

TEST(SlabAnalyses, RadiographyRefusesSlabsOutOfOrderOrMissing) {
  const Stored& s = cases()[1];
  RadiographyAccumulator image(s.volume.grid(), 2);
  EXPECT_THROW(image.add(3, s.volume), std::logic_error);
  RadiographyAccumulator partial(s.volume.grid(), 2);
  EXPECT_THROW(partial.take(), std::logic_error);
  // All slabs one way: the seam along z is kept as bits or as runs.
  RadiographyAccumulator mixed(s.volume.grid(), 2);
  Grid first = s.volume.grid();
  first.dims.z = 1;
  mixed.add(0, BitVolume(first));
  Grid rest = s.volume.grid();
  rest.dims.z -= 1;
  try {
    mixed.add(1, RunSlab(rest));
    ADD_FAILURE() << "took bits then runs";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("all its slabs as bits or all as runs"), std::string::npos) << e.what();
  }
}

TEST(SlabAnalyses, PartsAndVoidsAreExactlyTheInMemoryOnes) {
  // A shell with a cavity and a loose ball inside it: one void, two parts,
  // found whether the slabs cut through the cavity or not.
  Grid g;
  g.dims = {30, 28, 33};
  BitVolume shell(g);
  for (std::int64_t k = 3; k < 29; ++k)
    for (std::int64_t j = 2; j < 25; ++j)
      for (std::int64_t i = 4; i < 27; ++i) {
        const bool wall = k < 6 || k >= 26 || j < 5 || j >= 22 || i < 7 || i >= 24;
        const std::int64_t di = i - 15, dj = j - 13, dk = k - 16;
        shell.set(i, j, k, wall || di * di + dj * dj + dk * dk <= 9);
      }
  VectorSink shell_rle;
  write_rle(shell, shell_rle);
  std::vector<const Stored*> all;
  for (const Stored& s : cases()) all.push_back(&s);
  Stored made{std::move(shell), shell_rle.data};
  all.push_back(&made);
  for (const Stored* s : all) {
    const ComponentReport expected = find_components(s->volume, 1);
    for (std::int64_t layers : slab_sizes(s->volume.grid())) {
      for (int threads : {1, 2}) {
        SCOPED_TRACE("layers " + std::to_string(layers) + ", threads " + std::to_string(threads));
        ComponentLabeller labeller(s->volume.grid(), threads), from_runs(s->volume.grid(), threads);
        read_rle_bit_slabs(s->rle, layers, [&](std::int64_t k0, const BitVolume& slab) { labeller.add(k0, slab); });
        read_rle_run_slabs(s->rle, layers, [&](std::int64_t k0, const RunSlab& slab) { from_runs.add(k0, slab); });
        for (const ComponentReport& got : {labeller.finish(), from_runs.finish()}) {
          ASSERT_EQ(got.parts.size(), expected.parts.size());
          ASSERT_EQ(got.voids.size(), expected.voids.size());
          auto same = [](const std::vector<VoxelRegion>& a, const std::vector<VoxelRegion>& b) {
            for (std::size_t r = 0; r < a.size(); ++r) {
              EXPECT_EQ(a[r].voxels, b[r].voxels);
              EXPECT_EQ(a[r].bbox_min, b[r].bbox_min);
              EXPECT_EQ(a[r].bbox_max, b[r].bbox_max);
              EXPECT_EQ(a[r].centroid, b[r].centroid);
            }
          };
          same(got.parts, expected.parts);
          same(got.voids, expected.voids);
        }
      }
    }
  }
  const ComponentReport r = find_components(made.volume);
  ASSERT_EQ(r.parts.size(), 2u);
  ASSERT_EQ(r.voids.size(), 1u);
  // The cavity: 17 x 17 x 20 voxels less the ball it holds.
  EXPECT_EQ(r.voids[0].voxels + r.parts[1].voxels, std::uint64_t{17 * 17 * 20});
}

TEST(SlabAnalyses, SectionsAlongEachAxisAreTheInMemoryOnes) {
  const Stored& s = cases()[0];
  const Grid& g = s.volume.grid();
  for (int axis = 0; axis < 3; ++axis) {
    for (std::int64_t index : {std::int64_t{0}, g.dims[axis] / 2, g.dims[axis] - 1}) {
      const GreyImage8 expected = cross_section(s.volume, axis, index);
      SectionGatherer section(g, axis, index);
      read_rle_bit_slabs(s.rle, 6, [&](std::int64_t k0, const BitVolume& slab) { section.add(k0, slab); });
      const GreyImage8 got = section.take();
      EXPECT_EQ(got.width, expected.width);
      EXPECT_EQ(got.pixels, expected.pixels) << "axis " << axis << " index " << index;
    }
  }
  EXPECT_THROW(SectionGatherer(g, 2, g.dims.z), Error);
}

// Each pixel of a section of random volumes against its voxel, from bits
// and from runs, for any slabs.
TEST(SlabAnalyses, SectionsOfRandomVolumesAreTheirVoxels) {
  for (const double density : {0.2, 0.5, 0.85}) {
    const Stored s = random_volume(density, 0x2545f4914f6cdd1du);
    const glm::i64vec3 d = s.volume.grid().dims;
    for (int axis = 0; axis < 3; ++axis) {
      const int ca = axis == 0 ? 1 : 0, ra = axis == 2 ? 1 : 2;  // as radiography's pixels
      for (std::int64_t index : {std::int64_t{0}, d[axis] / 2, d[axis] - 1}) {
        std::vector<std::uint8_t> voxels;
        for (std::int64_t r = 0; r < d[ra]; ++r)
          for (std::int64_t c = 0; c < d[ca]; ++c) {
            std::int64_t ijk[3];
            ijk[axis] = index;
            ijk[ca] = c;
            ijk[ra] = r;
            voxels.push_back(s.volume.get(ijk[0], ijk[1], ijk[2]) ? 255 : 0);
          }
        for (std::int64_t layers : {std::int64_t{1}, std::int64_t{4}, d.z}) {
          SCOPED_TRACE("axis " + std::to_string(axis) + " index " + std::to_string(index) + " layers " +
                       std::to_string(layers));
          SectionGatherer from_bits(s.volume.grid(), axis, index), from_runs(s.volume.grid(), axis, index);
          read_rle_bit_slabs(s.rle, layers, [&](std::int64_t k0, const BitVolume& slab) { from_bits.add(k0, slab); });
          read_rle_run_slabs(s.rle, layers, [&](std::int64_t k0, const RunSlab& slab) { from_runs.add(k0, slab); });
          EXPECT_EQ(from_bits.take().pixels, voxels);
          EXPECT_EQ(from_runs.take().pixels, voxels);
        }
      }
    }
  }
}

// The visible voxel of a pixel, walked voxel by voxel from the camera: the
// independent check of the renderer's run transitions and word scans.
std::int64_t first_filled(const BitVolume& v, View view, std::int64_t column, std::int64_t row) {
  const ViewBasis b = view_basis(view);
  const glm::i64vec3 d = v.grid().dims;
  std::int64_t ijk[3];
  ijk[b.right_axis] = b.right_positive ? column : d[b.right_axis] - 1 - column;
  ijk[b.up_axis] = b.up_positive ? d[b.up_axis] - 1 - row : row;
  for (std::int64_t s = 0; s < d[view.axis]; ++s) {
    ijk[view.axis] = view.from_positive ? d[view.axis] - 1 - s : s;
    if (v.get(ijk[0], ijk[1], ijk[2])) return ijk[0] + d.x * (ijk[1] + d.y * ijk[2]);
  }
  return -1;
}

TEST(SlabAnalyses, PreviewsFromEverySideAreExactlyTheInMemoryOnes) {
  for (const Stored& s : cases()) {
    const Grid& g = s.volume.grid();
    for (int axis = 0; axis < 3; ++axis)
      for (bool from_positive : {true, false}) {
        const View view{axis, from_positive};
        const PreviewImage expected = render_preview(s.volume, view, 1);
        std::int64_t seen = 0;
        for (std::int64_t r = 0; r < expected.height; ++r)
          for (std::int64_t c = 0; c < expected.width; ++c) {
            const std::int64_t voxel = expected.voxel[static_cast<std::size_t>(r * expected.width + c)];
            ASSERT_EQ(voxel, first_filled(s.volume, view, c, r)) << to_string(view) << " pixel " << c << "," << r;
            seen += voxel >= 0;
          }
        EXPECT_GT(seen, 0);
        for (std::int64_t layers : slab_sizes(g)) {
          SCOPED_TRACE(to_string(view) + " layers " + std::to_string(layers));
          PreviewRenderer renderer(g, view, 2);
          read_rle_bit_slabs(s.rle, layers, [&](std::int64_t k0, const BitVolume& slab) { renderer.find(k0, slab); });
          read_rle_bit_slabs(s.rle, layers, [&](std::int64_t k0, const BitVolume& slab) { renderer.shade(k0, slab); });
          const PreviewImage got = renderer.take();
          EXPECT_EQ(got.voxel, expected.voxel);
          EXPECT_EQ(got.shade, expected.shade);
          ASSERT_EQ(got.normal.size(), expected.normal.size());
          EXPECT_EQ(std::memcmp(got.normal.data(), expected.normal.data(), got.normal.size() * sizeof(glm::vec3)), 0);
          if (layers == 7) {
            EXPECT_EQ(preview_png(got, g, view, {}), preview_png(s.volume, view, nullptr, {}));
          }
          // The same stored volume read as runs: the same image.
          PreviewRenderer from_runs(g, view, 2);
          read_rle_run_slabs(s.rle, layers, [&](std::int64_t k0, const RunSlab& slab) { from_runs.find(k0, slab); });
          read_rle_run_slabs(s.rle, layers, [&](std::int64_t k0, const RunSlab& slab) { from_runs.shade(k0, slab); });
          const PreviewImage runs = from_runs.take();
          EXPECT_EQ(runs.voxel, expected.voxel);
          EXPECT_EQ(runs.shade, expected.shade);
          ASSERT_EQ(runs.normal.size(), expected.normal.size());
          EXPECT_EQ(std::memcmp(runs.normal.data(), expected.normal.data(), runs.normal.size() * sizeof(glm::vec3)), 0);
        }
      }
  }
}

// Random voxels filling the grid to its faces: rays blocked at the first
// layer, runs open at the last, neighbours outside the grid, single-voxel
// runs and gaps, each slab size's seams.
TEST(SlabAnalyses, PreviewsOfRandomVolumesFromRunsAndBitsAreTheInMemoryOnes) {
  for (const double density : {0.2, 0.5, 0.85}) {
    const Stored s = random_volume(density, 0x9e3779b97f4a7c15u);
    const Grid& g = s.volume.grid();
    const BitVolume& volume = s.volume;
    const std::vector<std::uint8_t>& rle = s.rle;
    for (int axis = 0; axis < 3; ++axis)
      for (bool from_positive : {true, false}) {
        const View view{axis, from_positive};
        const PreviewImage expected = render_preview(volume, view, 1);
        for (std::int64_t r = 0; r < expected.height; ++r)
          for (std::int64_t c = 0; c < expected.width; ++c)
            ASSERT_EQ(expected.voxel[static_cast<std::size_t>(r * expected.width + c)], first_filled(volume, view, c, r));
        // Full size, and shrunk as made (max_side) against shrink_preview
        // of the full image: blocks of 2, 3 and 8 pixels a side.
        for (const int max_side : {0, 40, 20, 9}) {
          const int factor = shrink_factor(expected.width, expected.height, max_side);
          const PreviewImage want = shrink_preview(expected, g, view, factor);
          ASSERT_EQ(want.block, factor);
          for (std::int64_t layers : {std::int64_t{1}, std::int64_t{2}, std::int64_t{5}, g.dims.z}) {
            SCOPED_TRACE(to_string(view) + " density " + std::to_string(density) + " layers " + std::to_string(layers) +
                         " max_side " + std::to_string(max_side));
            PreviewRenderer from_bits(g, view, 2, max_side), from_runs(g, view, 2, max_side);
            read_rle_bit_slabs(rle, layers, [&](std::int64_t k0, const BitVolume& slab) { from_bits.find(k0, slab); });
            read_rle_bit_slabs(rle, layers, [&](std::int64_t k0, const BitVolume& slab) { from_bits.shade(k0, slab); });
            read_rle_run_slabs(rle, layers, [&](std::int64_t k0, const RunSlab& slab) { from_runs.find(k0, slab); });
            read_rle_run_slabs(rle, layers, [&](std::int64_t k0, const RunSlab& slab) { from_runs.shade(k0, slab); });
            for (const PreviewImage& got : {from_bits.take(), from_runs.take(), render_preview(volume, view, 2, max_side)}) {
              EXPECT_EQ(got.width, want.width);
              EXPECT_EQ(got.height, want.height);
              EXPECT_EQ(got.block, want.block);
              EXPECT_EQ(got.voxel, want.voxel);
              EXPECT_EQ(got.shade, want.shade);
              ASSERT_EQ(got.normal.size(), want.normal.size());
              EXPECT_EQ(std::memcmp(got.normal.data(), want.normal.data(), got.normal.size() * sizeof(glm::vec3)), 0);
            }
          }
        }
      }
  }
}

// An image of over 2^17 visible pixels: the renderer's layer sort runs in
// chunks on every thread. Every visible pixel's normal is then computed
// (a unit vector: a pixel the sort lost would keep a zero one), the same
// from slabs of one layer and from the whole volume, at full size and
// shrunk.
TEST(SlabAnalyses, PreviewsOfLargeImagesShadeEveryVisiblePixel) {
  Grid g;
  g.dims = {420, 400, 6};
  g.voxel_size = 0.5;
  BitVolume volume(g);
  std::uint64_t state = 0x6a09e667f3bcc909u;
  for (std::int64_t k = 0; k < g.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        if (state % 3 != 0) volume.set(i, j, k, true);
      }
  VectorSink sink;
  write_rle(volume, sink);
  for (const int max_side : {0, 200}) {
    const PreviewImage whole = render_preview(volume, View{2, true}, 2, max_side);
    std::int64_t visible = 0;
    for (std::size_t p = 0; p < whole.voxel.size(); ++p) {
      if (whole.voxel[p] < 0) continue;
      ++visible;
      ASSERT_NEAR(glm::length(whole.normal[p]), 1.0f, 1e-5f) << "pixel " << p << " max_side " << max_side;
    }
    // Full size over 2^17 pixels; shrunk by 3, over 2^17 / 9 blocks of 9 normals.
    EXPECT_GT(visible * (max_side == 0 ? 1 : 9), std::int64_t{1} << 17);
    PreviewRenderer layers(g, View{2, true}, 2, max_side);
    read_rle_run_slabs(sink.data, 1, [&](std::int64_t k0, const RunSlab& slab) { layers.find(k0, slab); });
    read_rle_run_slabs(sink.data, 1, [&](std::int64_t k0, const RunSlab& slab) { layers.shade(k0, slab); });
    const PreviewImage got = layers.take();
    EXPECT_EQ(got.voxel, whole.voxel);
    EXPECT_EQ(got.shade, whole.shade);
  }
}

TEST(SlabAnalyses, PreviewRefusesSlabsOutOfOrderOrAPassMissing) {
  const Stored& s = cases()[1];
  const Grid& g = s.volume.grid();
  PreviewRenderer renderer(g, View{2, true});
  EXPECT_THROW(renderer.find(3, s.volume), std::logic_error);
  EXPECT_THROW(renderer.shade(0, s.volume), std::logic_error);  // before find() saw every layer
  renderer.find(0, s.volume);
  EXPECT_THROW(renderer.take(), std::logic_error);  // shade() has not run
  EXPECT_THROW(PreviewRenderer(g, View{3, true}), Error);
  // Shrunk by a factor of 2, 46000^2 pixels are 529 million blocks of 9
  // raw normals: more than 32 bits count, refused before anything is held.
  Grid huge = g;
  huge.dims = {46000, 46000, 1};
  try {
    PreviewRenderer(huge, View{2, true}, 1, 40000);
    ADD_FAILURE() << "a preview of 529 million blocks was taken on";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::limit_exceeded);
    EXPECT_NE(std::string(e.what()).find("ask for a smaller size"), std::string::npos) << e.what();
  }
  // A pass takes its slabs one way: its seam is kept as bits or as runs.
  PreviewRenderer mixed(g, View{2, true});
  Grid half = g;
  half.dims.z = g.dims.z / 2;
  BitVolume lower(half);
  for (std::int64_t k = 0; k < half.dims.z; ++k)
    for (std::int64_t j = 0; j < g.dims.y; ++j)
      for (std::int64_t i = 0; i < g.dims.x; ++i) lower.set(i, j, k, s.volume.get(i, j, k));
  mixed.find(0, lower);
  half.dims.z = g.dims.z - half.dims.z;
  try {
    mixed.find(g.dims.z / 2, RunSlab(half));
    ADD_FAILURE() << "a pass took bits then runs";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("all its slabs as bits or all as runs"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace voxd
