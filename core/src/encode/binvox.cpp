// Patrick Min's binvox format (https://www.patrickmin.com/binvox/binvox.html):
//
//   #binvox 1            (2 for 8-bit values)
//   dim D D D
//   translate tx ty tz
//   scale s
//   data
//   (value, count) byte pairs, count 1..255, runs continuing across rows
//
// The voxel order is y fastest, then z, then x: index = x*D*D + z*D + y. A
// voxel (i, j, k) maps to model space as ((i + 0.5) / D * s + tx, ...), so with
// translate = origin and scale = D * voxel_size the centres are voxd's. The
// format is cubic: a non-cubic grid is padded with empty voxels up to
// D = max(dims) on the high side of each axis, keeping origin and voxel size.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "encode/bit_runs.h"
#include "encode/bit_transpose.h"
#include "encode/byte_buffer.h"
#include "encode/ordered_pipeline.h"
#include "encode/volume_checks.h"
#include "voxd/encode/number_text.h"
#include "voxd/parallel.h"
#include "voxd/encode/volume_format.h"

namespace voxd {
namespace {

using encode::ByteBuffer;

constexpr std::size_t kFlushBytes = std::size_t{1} << 20;
// Below this volume size, starting threads costs more than the encoding.
constexpr std::size_t kParallelMinBytes = std::size_t{1} << 20;
// Word columns gathered ahead of the run emission (at least 2 when parallel).
constexpr std::size_t kColumnBufferBytes = std::size_t{16} << 20;
// Longest header a reader scans for its "data" line; real headers are ~60 bytes.
constexpr std::size_t kMaxHeaderBytes = 64 * 1024;
constexpr std::string_view kMagic = "#binvox";

// ---------------------------------------------------------------- writing --

std::string make_header(const Grid& grid, std::int64_t d, int version) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(grid.origin[a]))
      throw Error(ErrorCode::invalid_argument, "binvox writer: the grid origin must be finite");
  const double scale = static_cast<double>(d) * grid.voxel_size;
  if (!std::isfinite(scale) || !(scale > 0.0))
    throw Error(ErrorCode::invalid_argument, "binvox writer: voxel_size must be positive and finite");
  const std::string dim = std::to_string(d);
  return "#binvox " + std::to_string(version) + "\ndim " + dim + " " + dim + " " + dim + "\ntranslate " +
         number_text(grid.origin.x) + " " + number_text(grid.origin.y) + " " + number_text(grid.origin.z) +
         "\nscale " + number_text(scale) + "\ndata\n";
}

std::int64_t cube_dim(const Grid& grid) { return std::max({grid.dims.x, grid.dims.y, grid.dims.z}); }

// Turns a voxel sequence, given as runs of any length, into binvox pairs.
class BinvoxRunWriter {
 public:
  explicit BinvoxRunWriter(ByteSink& sink) : sink_(sink) {}

  void add(std::uint8_t value, std::uint64_t n) {
    if (n == 0) return;
    if (value != value_ && count_ > 0) {
      out_.put_pairs(value_, static_cast<std::uint8_t>(count_), 1);
      count_ = 0;
    }
    value_ = value;
    count_ += n;
    // Emit full pairs as the run grows, so one long run (an empty volume is
    // a single run of D^3) never needs more than the pairs it produces.
    if (count_ >= 255) {
      out_.put_pairs(value_, 255, static_cast<std::size_t>(count_ / 255));
      count_ %= 255;
    }
  }
  void flush_if_large() {
    if (out_.size() < kFlushBytes) return;
    sink_.write(out_.bytes());
    out_.reset();
  }
  void finish() {
    if (count_ > 0) out_.put_pairs(value_, static_cast<std::uint8_t>(count_), 1);
    count_ = 0;
    sink_.write(out_.bytes());
    out_.reset();
  }

 private:
  ByteSink& sink_;
  ByteBuffer out_;
  std::uint8_t value_ = 0;
  std::uint64_t count_ = 0;  // pending voxels of value_, below 255 between calls
};

// Copies one 64-wide word column of the volume (x in [64w, 64w + 64)) into 64
// bit-packed x-slabs: slab b holds, for each z, a row of ny bits (y fastest)
// padded to y_words words, i.e. the binvox order of x = 64w + b.
void gather_x_slabs(const BitVolume& volume, std::int64_t w, std::int64_t y_words, std::uint64_t* x_slabs) {
  const std::int64_t ny = volume.grid().dims.y;
  const std::int64_t nz = volume.grid().dims.z;
  const auto slab_words = static_cast<std::size_t>(nz * y_words);
  std::uint64_t block[64];
  for (std::int64_t z = 0; z < nz; ++z) {
    for (std::int64_t yb = 0; yb < y_words; ++yb) {
      const std::int64_t rows = std::min<std::int64_t>(64, ny - yb * 64);
      std::uint64_t any = 0, all = ~std::uint64_t{0};
      for (std::int64_t t = 0; t < rows; ++t) {
        block[t] = volume.row(yb * 64 + t, z)[w];
        any |= block[t];
        all &= block[t];
      }
      std::fill(block + rows, block + 64, 0);
      const auto at = static_cast<std::size_t>(z * y_words + yb);
      if (any == 0 || (all == ~std::uint64_t{0} && rows == 64)) {
        // Uniform block (inside or outside a solid: most of them), its own
        // transpose. The bits past nx are 0 in every row, so a block of a
        // last, partial column is never all ones.
        for (std::size_t b = 0; b < 64; ++b) x_slabs[b * slab_words + at] = any;
        continue;
      }
      encode::transpose_64x64(block);  // now bit t of block[b] = voxel (64w + b, 64yb + t, z)
      for (std::size_t b = 0; b < 64; ++b) x_slabs[b * slab_words + at] = block[b];
    }
  }
}

// Length of the run of bytes equal to row[begin].
std::int64_t byte_run(const std::uint8_t* row, std::int64_t begin, std::int64_t n) {
  std::int64_t i = begin + 1;
  while (i < n && row[i] == row[begin]) ++i;
  return i - begin;
}

// ---------------------------------------------------------------- reading --

struct BinvoxHeader {
  int version = 1;
  std::int64_t dim = 0;
  glm::dvec3 translate{0.0};
  double scale = 1.0;  // the reference reader's default when the line is absent
  std::size_t data_offset = 0;
};

[[noreturn]] void malformed(const std::string& message) {
  throw Error(ErrorCode::malformed_input, "binvox: " + message);
}
[[noreturn]] void truncated(const std::string& message) {
  throw Error(ErrorCode::truncated_input, "binvox: " + message);
}

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r') ++j;
    if (j > i) words.push_back(line.substr(i, j - i));
    i = j;
  }
  return words;
}

template <typename T>
T header_number(std::string_view word, std::string_view line) {
  const std::optional<T> parsed = voxd::parse_number<T>(word);
  if (!parsed) malformed("bad number \"" + std::string(word) + "\" in header line \"" + std::string(line) + "\"");
  const T value = *parsed;
  if constexpr (std::is_floating_point_v<T>)
    if (!std::isfinite(value)) malformed("non-finite number in header line \"" + std::string(line) + "\"");
  return value;
}

void expect_words(const std::vector<std::string_view>& words, std::size_t n, std::string_view line) {
  if (words.size() != n)
    malformed("header line \"" + std::string(line) + "\" needs " + std::to_string(n - 1) + " values");
}

// Header lines may come in any order and unknown ones are skipped, as the
// reference reader does; "dim" is required, translate and scale default to
// 0 and 1. Non-cubic dims are refused: readers disagree on their axis order.
BinvoxHeader parse_header(std::span<const std::uint8_t> data) {
  const std::string_view text(reinterpret_cast<const char*>(data.data()), std::min(data.size(), kMaxHeaderBytes));
  if (!text.starts_with(kMagic)) {
    if (kMagic.starts_with(text)) truncated("the data ends inside the \"#binvox\" magic");
    malformed("not a binvox file (it does not start with \"#binvox\")");
  }
  BinvoxHeader header;
  bool have_dim = false;
  std::size_t pos = 0;
  for (bool first_line = true;; first_line = false) {
    const std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) {
      if (data.size() >= kMaxHeaderBytes)
        malformed("no \"data\" line in the first " + std::to_string(kMaxHeaderBytes) + " bytes");
      truncated("the data ends inside the header, before its \"data\" line");
    }
    const std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    const auto words = split_words(line);
    if (first_line) {
      if (words.size() != 2 || words[0] != kMagic)
        malformed("the first line must be \"#binvox <version>\", found \"" + std::string(line) + "\"");
      header.version = header_number<int>(words[1], line);
      if (header.version != 1 && header.version != 2)
        malformed("version " + std::string(words[1]) + " is not supported (this reader reads 1 and 2)");
      continue;
    }
    if (words.empty()) continue;
    if (words[0] == "dim") {
      expect_words(words, 4, line);
      std::int64_t d[3];
      for (int a = 0; a < 3; ++a) {
        d[a] = header_number<std::int64_t>(words[static_cast<std::size_t>(a) + 1], line);
        if (d[a] < 1 || d[a] > kMaxGridDim)
          malformed("dim " + std::to_string(d[a]) + " is out of range 1.." + std::to_string(kMaxGridDim));
      }
      if (d[0] != d[1] || d[0] != d[2])
        malformed("non-cubic dims \"" + std::string(line) +
                  "\" are not supported: binvox readers disagree on which axis is which");
      header.dim = d[0];
      have_dim = true;
    } else if (words[0] == "translate") {
      expect_words(words, 4, line);
      for (int a = 0; a < 3; ++a) header.translate[a] = header_number<double>(words[static_cast<std::size_t>(a) + 1], line);
    } else if (words[0] == "scale") {
      expect_words(words, 2, line);
      header.scale = header_number<double>(words[1], line);
      if (!(header.scale > 0.0)) malformed("scale must be positive, found \"" + std::string(words[1]) + "\"");
    } else if (words[0] == "data") {
      expect_words(words, 1, line);
      break;
    }
  }
  if (!have_dim) malformed("the header has no \"dim\" line");
  header.data_offset = pos;
  return header;
}

// Walks the (value, count) pairs until they cover D^3 voxels, calling
// on_run(first_index, count, value). Bytes after the last voxel are ignored,
// as by the reference reader.
template <class OnRun>
void walk_runs(std::span<const std::uint8_t> data, const BinvoxHeader& header, const OnRun& on_run) {
  const auto d = static_cast<std::uint64_t>(header.dim);
  const std::uint64_t total = d * d * d;
  std::uint64_t covered = 0;
  std::size_t pos = header.data_offset;
  while (covered < total) {
    if (data.size() - pos < 2)
      truncated("the data ends after " + std::to_string(covered) + " of the " + std::to_string(total) + " voxels");
    const std::uint8_t value = data[pos];
    const std::uint8_t count = data[pos + 1];
    if (count > total - covered)
      malformed("the run at byte " + std::to_string(pos) + " goes past the last of the " + std::to_string(total) +
                " voxels");
    on_run(covered, count, value);
    covered += count;
    pos += 2;
  }
}

// Splits the run of binvox indices [first, first + count) into pieces that lie
// in one binvox row (fixed x and z), calling on_piece(x, z, y, n) for y in
// [y, y + n).
template <class OnPiece>
void split_run(std::int64_t d, std::uint64_t first, std::uint64_t count, const OnPiece& on_piece) {
  const auto ud = static_cast<std::uint64_t>(d);
  while (count > 0) {
    const auto y = static_cast<std::int64_t>(first % ud);
    const auto z = static_cast<std::int64_t>((first / ud) % ud);
    const auto x = static_cast<std::int64_t>(first / (ud * ud));
    const std::uint64_t n = std::min<std::uint64_t>(count, static_cast<std::uint64_t>(d - y));
    on_piece(x, z, y, static_cast<std::int64_t>(n));
    first += n;
    count -= n;
  }
}

// The inverse of gather_x_slabs: moves 64 bit-packed x-slabs back into word
// column w of the volume, and clears them.
void scatter_x_slabs(std::uint64_t* x_slabs, std::int64_t w, std::int64_t y_words, BitVolume& volume) {
  const std::int64_t ny = volume.grid().dims.y;
  const std::int64_t nz = volume.grid().dims.z;
  const auto slab_words = static_cast<std::size_t>(nz * y_words);
  std::uint64_t block[64];
  for (std::int64_t z = 0; z < nz; ++z) {
    for (std::int64_t yb = 0; yb < y_words; ++yb) {
      const auto at = static_cast<std::size_t>(z * y_words + yb);
      std::uint64_t any = 0;
      for (std::size_t b = 0; b < 64; ++b) {
        block[b] = x_slabs[b * slab_words + at];
        any |= block[b];
        x_slabs[b * slab_words + at] = 0;
      }
      if (any == 0) continue;  // the volume is still zero there
      encode::transpose_64x64(block);  // now bit b of block[t] = voxel (64w + b, 64yb + t, z)
      const std::int64_t rows = std::min<std::int64_t>(64, ny - yb * 64);
      for (std::int64_t t = 0; t < rows; ++t) volume.row(yb * 64 + t, z)[w] = block[t];
    }
  }
}

Grid grid_of(const BinvoxHeader& header) {
  Grid grid;
  grid.dims = glm::i64vec3(header.dim);
  grid.origin = header.translate;
  grid.voxel_size = header.scale / static_cast<double>(header.dim);
  return grid;
}

}  // namespace

void write_binvox(const BitVolume& volume, ByteSink& sink) {
  encode::require_voxels(volume.grid(), "binvox writer");
  const Grid& grid = volume.grid();
  const std::int64_t d = cube_dim(grid);
  const std::string header = make_header(grid, d, 1);
  sink.write(header.data(), header.size());

  const std::int64_t nx = grid.dims.x, ny = grid.dims.y, nz = grid.dims.z;
  const auto ud = static_cast<std::uint64_t>(d);
  const std::int64_t y_words = (ny + 63) / 64;
  const auto slab_words = static_cast<std::size_t>(nz * y_words);

  // Word columns are gathered a few ahead on worker threads while the calling
  // thread turns the previous ones into runs: the two phases overlap with no
  // barrier, and memory stays at `slots` columns.
  const int threads = volume.byte_size() < kParallelMinBytes ? 1 : default_thread_count();
  const std::size_t column_bytes = 64 * slab_words * sizeof(std::uint64_t);
  const std::size_t slots =
      threads == 1 ? 1
                   : std::clamp<std::size_t>(kColumnBufferBytes / column_bytes, 2, static_cast<std::size_t>(threads) + 1);
  std::vector<std::vector<std::uint64_t>> columns(slots);

  BinvoxRunWriter pairs(sink);
  encode::BitRunSplitter runs;
  const auto emit = [&pairs](bool value, std::uint64_t n) { pairs.add(value ? 1 : 0, n); };
  encode::run_ordered_pipeline(
      volume.row_words(), threads, slots,
      [&](std::int64_t w, std::size_t slot) {
        columns[slot].resize(64 * slab_words);
        gather_x_slabs(volume, w, y_words, columns[slot].data());
      },
      [&](std::int64_t w, std::size_t slot) {
        for (std::int64_t b = 0; b < 64 && 64 * w + b < nx; ++b) {
          const std::uint64_t* x_slab = columns[slot].data() + static_cast<std::size_t>(b) * slab_words;
          for (std::int64_t z = 0; z < nz; ++z) {
            runs.add_row(x_slab + z * y_words, ny, emit);
            runs.add_zeros(static_cast<std::uint64_t>(d - ny), emit);
          }
          runs.add_zeros(static_cast<std::uint64_t>(d - nz) * ud, emit);
          pairs.flush_if_large();
        }
      });
  runs.add_zeros(static_cast<std::uint64_t>(d - nx) * ud * ud, emit);
  runs.finish(emit);
  pairs.finish();
}

void write_binvox(const DenseVolume<std::uint8_t>& volume, ByteSink& sink) {
  encode::require_voxels(volume, "binvox writer");
  const Grid& grid = volume.grid();
  const std::int64_t d = cube_dim(grid);
  const std::string header = make_header(grid, d, 2);
  sink.write(header.data(), header.size());

  const std::int64_t nx = grid.dims.x, ny = grid.dims.y, nz = grid.dims.z;
  const auto ud = static_cast<std::uint64_t>(d);
  // binvox's outer axis is x, DenseVolume's inner one: copy a block of x
  // values at a time into x-major order (y fastest within each x-slab).
  constexpr std::int64_t kXBlock = 16;
  const auto slab_size = static_cast<std::size_t>(ny * nz);
  std::vector<std::uint8_t> x_slabs(static_cast<std::size_t>(kXBlock) * slab_size);

  BinvoxRunWriter pairs(sink);
  for (std::int64_t x0 = 0; x0 < nx; x0 += kXBlock) {
    const std::int64_t width = std::min(kXBlock, nx - x0);
    for (std::int64_t z = 0; z < nz; ++z) {
      const std::uint8_t* slab = volume.slab(z);
      for (std::int64_t y = 0; y < ny; ++y) {
        const std::uint8_t* src = slab + y * nx + x0;
        const auto at = static_cast<std::size_t>(z * ny + y);
        for (std::int64_t b = 0; b < width; ++b) x_slabs[static_cast<std::size_t>(b) * slab_size + at] = src[b];
      }
    }
    for (std::int64_t b = 0; b < width; ++b) {
      const std::uint8_t* x_slab = x_slabs.data() + static_cast<std::size_t>(b) * slab_size;
      for (std::int64_t z = 0; z < nz; ++z) {
        const std::uint8_t* row = x_slab + z * ny;
        for (std::int64_t y = 0; y < ny;) {
          const std::int64_t n = byte_run(row, y, ny);
          pairs.add(row[y], static_cast<std::uint64_t>(n));
          y += n;
        }
        pairs.add(0, static_cast<std::uint64_t>(d - ny));
      }
      pairs.add(0, static_cast<std::uint64_t>(d - nz) * ud);
      pairs.flush_if_large();
    }
  }
  pairs.add(0, static_cast<std::uint64_t>(d - nx) * ud * ud);
  pairs.finish();
}

BitVolume read_binvox(std::span<const std::uint8_t> data, const ReadLimits& limits) {
  const BinvoxHeader header = parse_header(data);
  walk_runs(data, header, [](std::uint64_t, std::uint64_t, std::uint8_t) {});  // validate before allocating
  const Grid grid = grid_of(header);
  encode::check_read_limit(encode::bit_volume_bytes(grid.dims), limits, "binvox reader");
  BitVolume volume(grid);

  // Runs arrive x-slab by x-slab; collect the 64 x-slabs of one word column
  // as bit rows, then transpose them into the volume (as the writer does,
  // reversed), instead of touching a different volume row for every voxel.
  const std::int64_t d = header.dim;
  const std::int64_t y_words = (d + 63) / 64;
  const auto slab_words = static_cast<std::size_t>(d * y_words);
  std::vector<std::uint64_t> x_slabs(64 * slab_words, 0);
  std::int64_t column = -1;  // word column held in x_slabs
  walk_runs(data, header, [&](std::uint64_t first, std::uint64_t count, std::uint8_t value) {
    if (value == 0) return;
    split_run(d, first, count, [&](std::int64_t x, std::int64_t z, std::int64_t y, std::int64_t n) {
      if (x >> 6 != column) {
        if (column >= 0) scatter_x_slabs(x_slabs.data(), column, y_words, volume);
        column = x >> 6;
      }
      encode::set_bit_range(x_slabs.data() + static_cast<std::size_t>(x & 63) * slab_words + z * y_words, y, y + n);
    });
  });
  if (column >= 0) scatter_x_slabs(x_slabs.data(), column, y_words, volume);
  return volume;
}

DenseVolume<std::uint8_t> read_binvox_u8(std::span<const std::uint8_t> data, const ReadLimits& limits) {
  const BinvoxHeader header = parse_header(data);
  walk_runs(data, header, [](std::uint64_t, std::uint64_t, std::uint8_t) {});  // validate before allocating
  const Grid grid = grid_of(header);
  encode::check_read_limit(grid.voxel_count(), limits, "binvox reader");
  DenseVolume<std::uint8_t> volume(grid, 0);

  // As in write_binvox for u8: a block of x-slabs (y fastest), copied into
  // the x-fastest volume once complete.
  constexpr std::int64_t kXBlock = 16;
  const std::int64_t d = header.dim;
  const auto slab_size = static_cast<std::size_t>(d * d);
  std::vector<std::uint8_t> x_slabs(static_cast<std::size_t>(kXBlock) * slab_size, 0);
  std::int64_t block = -1;  // x block held in x_slabs
  const auto flush = [&] {
    const std::int64_t x0 = block * kXBlock;
    const std::int64_t width = std::min(kXBlock, d - x0);
    for (std::int64_t z = 0; z < d; ++z) {
      for (std::int64_t y = 0; y < d; ++y) {
        std::uint8_t* dst = &volume.at(x0, y, z);
        const auto at = static_cast<std::size_t>(z * d + y);
        for (std::int64_t b = 0; b < width; ++b) dst[b] = x_slabs[static_cast<std::size_t>(b) * slab_size + at];
      }
    }
    std::fill(x_slabs.begin(), x_slabs.end(), 0);
  };
  walk_runs(data, header, [&](std::uint64_t first, std::uint64_t count, std::uint8_t value) {
    if (value == 0) return;
    split_run(d, first, count, [&](std::int64_t x, std::int64_t z, std::int64_t y, std::int64_t n) {
      if (x / kXBlock != block) {
        if (block >= 0) flush();
        block = x / kXBlock;
      }
      std::fill_n(x_slabs.data() + static_cast<std::size_t>(x % kXBlock) * slab_size + z * d + y, n, value);
    });
  });
  if (block >= 0) flush();
  return volume;
}

}  // namespace voxd
