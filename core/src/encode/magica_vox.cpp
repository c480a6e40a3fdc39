// MagicaVoxel .vox writing (https://github.com/ephtracy/voxel-model:
// MagicaVoxel-file-format-vox.txt and -vox-extension.txt). Every chunk is
// id, content bytes N, children bytes M (little-endian int32), content,
// children; the file is "VOX ", 150, then the MAIN chunk holding all others
// as children. MAIN's header needs the size of everything after it, so the
// volume is scanned once first (palette, filled voxels per block), then the
// models are streamed block by block.
#include "voxd/encode/magica_vox.h"

#include <algorithm>
#include <array>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "voxd/error.h"

namespace voxd {
namespace {

constexpr std::int64_t kBlock = 256;  // a model's largest extent per axis
constexpr int kBlockShift = 8;
constexpr std::size_t kMaxColours = 255;  // palette indices 1..255; 0 is "empty"
constexpr std::uint64_t kMaxFileBytes = 0x7FFFFFFF;  // chunk sizes are signed int32
constexpr std::size_t kFlushBytes = std::size_t{1} << 20;
constexpr std::size_t kChunkHeaderBytes = 12;
constexpr std::size_t kSizeChunkBytes = kChunkHeaderBytes + 12;
constexpr std::size_t kRgbaChunkBytes = kChunkHeaderBytes + 4 * 256;

std::uint32_t pack(Rgba8 c) {
  return std::uint32_t{c.r} | std::uint32_t{c.g} << 8 | std::uint32_t{c.b} << 16 | std::uint32_t{c.a} << 24;
}

// Little-endian output into a buffer that goes to the sink about once per
// MiB, so a large model never sits whole in memory. Without a sink it only
// collects (chunks whose size must be known before they are written).
class Out {
 public:
  explicit Out(ByteSink* sink = nullptr) : sink_(sink) {}
  void u8(std::uint8_t v) { buf_.push_back(v); }
  void i32(std::int64_t v) {
    const auto u = static_cast<std::uint32_t>(v);  // two's complement for -1
    for (int shift = 0; shift < 32; shift += 8) buf_.push_back(static_cast<std::uint8_t>(u >> shift));
  }
  void id(std::string_view four) { buf_.insert(buf_.end(), four.begin(), four.end()); }
  void chunk(std::string_view four, std::uint64_t content, std::uint64_t children) {
    id(four);
    i32(static_cast<std::int64_t>(content));
    i32(static_cast<std::int64_t>(children));
  }
  // The extension's STRING: int32 length, then the bytes without NUL.
  void string(std::string_view s) {
    i32(static_cast<std::int64_t>(s.size()));
    id(s);
  }
  void bytes(const std::vector<std::uint8_t>& b) { buf_.insert(buf_.end(), b.begin(), b.end()); }
  void maybe_flush() {
    if (buf_.size() >= kFlushBytes) flush();
  }
  void flush() {
    if (sink_ == nullptr) return;
    if (!buf_.empty()) sink_->write(buf_);
    buf_.clear();
  }
  std::vector<std::uint8_t>& buffer() { return buf_; }

 private:
  ByteSink* sink_;
  std::vector<std::uint8_t> buf_;
};

// ------------------------------------------------------------- palette --

// Median cut (the header's steps 1 to 3) on the histogram of the filled voxels.
class MedianCut {
 public:
  static std::uint32_t cell_of(Rgba8 c) {
    return std::uint32_t{c.r} >> 3 | (std::uint32_t{c.g} >> 3) << 5 | (std::uint32_t{c.b} >> 3) << 10 |
           (std::uint32_t{c.a} >> 3) << 15;
  }
  static constexpr std::size_t kCells = std::size_t{1} << 20;

  explicit MedianCut(const DenseVolume<Rgba8>& volume) : slot_(kCells, -1) {
    // Counts first, so the per-cell sums are kept for occupied cells only.
    std::vector<std::uint32_t> counts(kCells, 0);
    for (const Rgba8 c : volume.values())
      if (c.a != 0) ++counts[cell_of(c)];
    for (std::uint32_t key = 0; key < kCells; ++key) {
      if (counts[key] == 0) continue;
      slot_[key] = static_cast<std::int32_t>(cells_.size());
      cells_.push_back(Cell{key, counts[key], {}, {}});
    }
    for (const Rgba8 c : volume.values()) {
      if (c.a == 0) continue;
      Cell& cell = cells_[static_cast<std::size_t>(slot_[cell_of(c)])];
      cell.sum[0] += c.r;
      cell.sum[1] += c.g;
      cell.sum[2] += c.b;
      cell.sum[3] += c.a;
    }
    for (Cell& cell : cells_)
      for (int ch = 0; ch < 4; ++ch) cell.mean[ch] = static_cast<double>(cell.sum[ch]) / cell.count;
  }

  // At most kMaxColours colours, box by box.
  std::vector<Rgba8> palette() {
    std::vector<std::uint32_t> order(cells_.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
    std::vector<Box> boxes = {measure(order, 0, order.size())};
    while (boxes.size() < kMaxColours) {
      std::size_t best = boxes.size();
      for (std::size_t b = 0; b < boxes.size(); ++b)
        if (boxes[b].end - boxes[b].begin >= 2 && (best == boxes.size() || boxes[b].score > boxes[best].score))
          best = b;
      if (best == boxes.size()) break;  // every box is a single cell
      const Box box = boxes[best];
      const int ch = box.channel;
      std::sort(order.begin() + static_cast<std::ptrdiff_t>(box.begin), order.begin() + static_cast<std::ptrdiff_t>(box.end),
                [&](std::uint32_t a, std::uint32_t b) {
                  const Cell& ca = cells_[a];
                  const Cell& cb = cells_[b];
                  return ca.mean[ch] != cb.mean[ch] ? ca.mean[ch] < cb.mean[ch] : ca.key < cb.key;
                });
      // First cut where the lower part holds at least half the voxels, kept
      // inside the box so both halves have a cell.
      std::uint64_t below = 0;
      std::size_t cut = box.begin + 1;
      for (std::size_t i = box.begin; i + 1 < box.end; ++i) {
        below += cells_[order[i]].count;
        cut = i + 1;
        if (2 * below >= box.count) break;
      }
      boxes[best] = measure(order, box.begin, cut);
      boxes.push_back(measure(order, cut, box.end));
    }
    std::vector<Rgba8> colours;
    colours.reserve(boxes.size());
    for (const Box& box : boxes) {
      std::array<std::uint64_t, 4> sum{};
      for (std::size_t i = box.begin; i < box.end; ++i)
        for (int ch = 0; ch < 4; ++ch) sum[ch] += cells_[order[i]].sum[ch];
      auto mean = [&](int ch) {
        return static_cast<std::uint8_t>((2 * sum[ch] + box.count) / (2 * box.count));  // rounded, half up
      };
      colours.push_back(Rgba8{mean(0), mean(1), mean(2), mean(3)});  // alpha stays >= 1: every voxel's is
    }
    return colours;
  }

  // Occupied cells in key order, and the slot of a colour's cell.
  std::size_t cell_count() const { return cells_.size(); }
  std::uint32_t key(std::size_t slot) const { return cells_[slot].key; }
  std::size_t slot(Rgba8 c) const { return static_cast<std::size_t>(slot_[cell_of(c)]); }

 private:
  struct Cell {
    std::uint32_t key;
    std::uint64_t count;
    std::array<std::uint64_t, 4> sum;
    std::array<double, 4> mean;
  };
  struct Box {
    std::size_t begin = 0, end = 0;  // range of `order`
    std::uint64_t count = 0;
    double score = 0.0;  // count-weighted squared deviation of the cell means
    int channel = 0;     // the channel contributing most to it
  };

  Box measure(const std::vector<std::uint32_t>& order, std::size_t begin, std::size_t end) const {
    Box box;
    box.begin = begin;
    box.end = end;
    std::array<double, 4> weighted{};
    for (std::size_t i = begin; i < end; ++i) {
      const Cell& c = cells_[order[i]];
      box.count += c.count;
      for (int ch = 0; ch < 4; ++ch) weighted[ch] += c.mean[ch] * static_cast<double>(c.count);
    }
    std::array<double, 4> deviation{};
    for (std::size_t i = begin; i < end; ++i) {
      const Cell& c = cells_[order[i]];
      for (int ch = 0; ch < 4; ++ch) {
        const double d = c.mean[ch] - weighted[ch] / static_cast<double>(box.count);
        deviation[ch] += d * d * static_cast<double>(c.count);
      }
    }
    for (int ch = 0; ch < 4; ++ch) {
      box.score += deviation[ch];
      if (deviation[ch] > deviation[box.channel]) box.channel = ch;
    }
    return box;
  }

  std::vector<std::int32_t> slot_;  // cell key -> index into cells_, -1 when empty
  std::vector<Cell> cells_;
};

// Nearest palette colour (the header's step 4). A colour's nearest entry is
// among its cell's candidates: the entries whose distance to the cell's box
// is at most the smallest farthest-corner distance of any entry, which every
// colour in the cell has to some entry. So each voxel compares a handful of
// entries instead of 255, with the same result.
class NearestColour {
 public:
  NearestColour(const MedianCut& cut, std::vector<Rgba8> palette) : cut_(cut), palette_(std::move(palette)) {
    start_.reserve(cut.cell_count() + 1);
    std::vector<std::pair<int, int>> near_far(palette_.size());  // (nearest, farthest) squared distance
    for (std::size_t s = 0; s < cut.cell_count(); ++s) {
      start_.push_back(static_cast<std::uint32_t>(candidates_.size()));
      const std::uint32_t key = cut.key(s);
      std::array<int, 4> lo{};
      for (int ch = 0; ch < 4; ++ch) lo[ch] = static_cast<int>((key >> (5 * ch)) & 31) << 3;
      int bound = 4 * 255 * 255 + 1;
      for (std::size_t p = 0; p < palette_.size(); ++p) {
        const std::array<int, 4> v = channels(palette_[p]);
        int near = 0, far = 0;
        for (int ch = 0; ch < 4; ++ch) {
          const int below = lo[ch] - v[ch], above = v[ch] - (lo[ch] + 7);
          const int gap = std::max({below, above, 0});
          const int span = std::max(v[ch] - lo[ch], lo[ch] + 7 - v[ch]);
          near += gap * gap;
          far += span * span;
        }
        near_far[p] = {near, far};
        bound = std::min(bound, far);
      }
      for (std::size_t p = 0; p < palette_.size(); ++p)
        if (near_far[p].first <= bound) candidates_.push_back(static_cast<std::uint8_t>(p));
    }
    start_.push_back(static_cast<std::uint32_t>(candidates_.size()));
  }

  // Palette index 1..255.
  std::uint8_t operator()(Rgba8 c) const {
    const std::size_t s = cut_.slot(c);
    const std::array<int, 4> v = channels(c);
    int best_distance = 0;
    std::uint8_t best = 0;
    for (std::uint32_t n = start_[s]; n < start_[s + 1]; ++n) {
      const std::uint8_t p = candidates_[n];
      const std::array<int, 4> q = channels(palette_[p]);
      int d = 0;
      for (int ch = 0; ch < 4; ++ch) d += (v[ch] - q[ch]) * (v[ch] - q[ch]);
      if (n == start_[s] || d < best_distance) {  // candidates ascend, so ties keep the lower index
        best_distance = d;
        best = p;
      }
    }
    return static_cast<std::uint8_t>(best + 1);
  }
  const std::vector<Rgba8>& palette() const { return palette_; }

 private:
  static std::array<int, 4> channels(Rgba8 c) { return {c.r, c.g, c.b, c.a}; }

  const MedianCut& cut_;
  std::vector<Rgba8> palette_;
  std::vector<std::uint32_t> start_;        // per cell slot: first candidate
  std::vector<std::uint8_t> candidates_;    // palette positions, ascending per cell
};

// -------------------------------------------------------------- blocks --

struct Scan {
  glm::i64vec3 blocks{0};
  std::vector<std::uint64_t> filled;  // per block, bx fastest
  std::vector<Rgba8> exact;           // distinct colours in order of appearance, while <= 255
  bool quantize = false;              // more than 255 distinct colours
};

Scan scan(const DenseVolume<Rgba8>& volume) {
  const glm::i64vec3 dims = volume.grid().dims;
  Scan s;
  for (int a = 0; a < 3; ++a) s.blocks[a] = (dims[a] + kBlock - 1) / kBlock;
  s.filled.assign(static_cast<std::size_t>(s.blocks.x * s.blocks.y * s.blocks.z), 0);
  std::unordered_map<std::uint32_t, std::uint8_t> seen;
  const Rgba8* v = volume.values().data();
  for (std::int64_t k = 0; k < dims.z; ++k) {
    for (std::int64_t j = 0; j < dims.y; ++j) {
      std::uint64_t* row = s.filled.data() + (k >> kBlockShift) * s.blocks.x * s.blocks.y + (j >> kBlockShift) * s.blocks.x;
      for (std::int64_t i = 0; i < dims.x; ++i, ++v) {
        if (v->a == 0) continue;
        ++row[i >> kBlockShift];
        if (s.quantize) continue;
        const auto [it, added] = seen.try_emplace(pack(*v), 0);
        if (!added) continue;
        if (s.exact.size() == kMaxColours) {
          s.quantize = true;
          s.exact.clear();
        } else {
          s.exact.push_back(*v);
          it->second = static_cast<std::uint8_t>(s.exact.size());
        }
      }
    }
  }
  return s;
}

std::string translation(const glm::i64vec3& corner, const glm::i64vec3& size) {
  return std::to_string(corner.x + size.x / 2) + " " + std::to_string(corner.y + size.y / 2) + " " +
         std::to_string(corner.z + size.z / 2);
}

struct Model {
  glm::i64vec3 corner{0};
  glm::i64vec3 size{1};
  std::uint64_t voxels = 0;
};

// nTRN/nGRP/nSHP chunks and the LAYR chunk, built in memory: they are small
// (about 100 bytes a model) and their size goes into MAIN's header.
std::vector<std::uint8_t> scene_chunks(const std::vector<Model>& models) {
  Out out;
  auto chunk = [&](std::string_view id, auto&& content) {
    Out body;
    content(body);
    out.chunk(id, body.buffer().size(), 0);
    out.bytes(body.buffer());
  };
  const std::int64_t n = static_cast<std::int64_t>(models.size());
  chunk("nTRN", [](Out& o) {
    o.i32(0);   // node id
    o.i32(0);   // attributes: none
    o.i32(1);   // child: the group
    o.i32(-1);  // reserved
    o.i32(-1);  // layer: the root belongs to none
    o.i32(1);   // frames
    o.i32(0);   // frame attributes: none (identity)
  });
  chunk("nGRP", [n](Out& o) {
    o.i32(1);
    o.i32(0);
    o.i32(n);
    for (std::int64_t m = 0; m < n; ++m) o.i32(2 + 2 * m);
  });
  for (std::int64_t m = 0; m < n; ++m) {
    const Model& model = models[static_cast<std::size_t>(m)];
    chunk("nTRN", [&](Out& o) {
      o.i32(2 + 2 * m);
      o.i32(0);
      o.i32(3 + 2 * m);
      o.i32(-1);
      o.i32(0);  // layer 0
      o.i32(1);
      o.i32(1);  // one frame attribute
      o.string("_t");
      o.string(translation(model.corner, model.size));
    });
    chunk("nSHP", [&](Out& o) {
      o.i32(3 + 2 * m);
      o.i32(0);
      o.i32(1);  // models: one
      o.i32(m);
      o.i32(0);  // model attributes: none
    });
  }
  chunk("LAYR", [](Out& o) {
    o.i32(0);
    o.i32(0);
    o.i32(-1);
  });
  return std::move(out.buffer());
}

std::uint64_t xyzi_chunk_bytes(std::uint64_t voxels) { return kChunkHeaderBytes + 4 + 4 * voxels; }

}  // namespace

void write_vox(const DenseVolume<Rgba8>& volume, ByteSink& sink) {
  const Grid& grid = volume.grid();
  if (grid.dims.x < 0 || grid.dims.y < 0 || grid.dims.z < 0)
    throw Error(ErrorCode::invalid_argument, "vox writer: the grid has negative dims");
  if (volume.values().size() != grid.voxel_count())
    throw Error(ErrorCode::invalid_argument, "vox writer: the volume holds " + std::to_string(volume.values().size()) +
                                                 " values for " + std::to_string(grid.voxel_count()) + " voxels");

  Scan s = scan(volume);
  std::vector<Model> models;
  for (std::int64_t bz = 0; bz < s.blocks.z; ++bz)
    for (std::int64_t by = 0; by < s.blocks.y; ++by)
      for (std::int64_t bx = 0; bx < s.blocks.x; ++bx) {
        const std::uint64_t n = s.filled[static_cast<std::size_t>(bx + s.blocks.x * (by + s.blocks.y * bz))];
        if (n == 0) continue;
        Model m;
        m.corner = {bx * kBlock, by * kBlock, bz * kBlock};
        for (int a = 0; a < 3; ++a) m.size[a] = std::min(kBlock, grid.dims[a] - m.corner[a]);
        m.voxels = n;
        models.push_back(m);
      }
  if (models.empty()) models.push_back(Model{});  // see the header: one empty 1 x 1 x 1 model

  const std::vector<std::uint8_t> scene = scene_chunks(models);
  std::uint64_t children = scene.size() + kRgbaChunkBytes;
  for (const Model& m : models) children += kSizeChunkBytes + xyzi_chunk_bytes(m.voxels);
  const std::uint64_t file_bytes = 8 + kChunkHeaderBytes + children;
  if (file_bytes > kMaxFileBytes)
    throw Error(ErrorCode::limit_exceeded, "vox writer: the file would be " + std::to_string(file_bytes) +
                                               " bytes, over the 2147483647 a .vox file can hold (chunk sizes are "
                                               "signed 32-bit); write fewer filled voxels or another format");

  // The palette, and how a voxel's colour becomes its index.
  std::vector<Rgba8> palette;
  std::unordered_map<std::uint32_t, std::uint8_t> exact_index;
  std::unique_ptr<MedianCut> cut;
  std::unique_ptr<NearestColour> nearest;
  if (s.quantize) {
    cut = std::make_unique<MedianCut>(volume);
    nearest = std::make_unique<NearestColour>(*cut, cut->palette());
    palette = nearest->palette();
  } else {
    palette = std::move(s.exact);
    for (std::size_t p = 0; p < palette.size(); ++p) exact_index.emplace(pack(palette[p]), static_cast<std::uint8_t>(p + 1));
  }
  // Neighbouring voxels mostly share a colour: remember the last one.
  std::uint32_t last_colour = 0;
  std::uint8_t last_index = 0;
  auto index_of = [&](Rgba8 c) {
    const std::uint32_t key = pack(c);
    if (last_index == 0 || key != last_colour) {
      last_colour = key;
      last_index = nearest ? (*nearest)(c) : exact_index.at(key);
    }
    return last_index;
  };

  Out out(&sink);
  out.id("VOX ");
  out.i32(150);
  out.chunk("MAIN", 0, children);
  for (const Model& m : models) {
    out.chunk("SIZE", 12, 0);
    for (int a = 0; a < 3; ++a) out.i32(m.size[a]);
    out.chunk("XYZI", 4 + 4 * m.voxels, 0);
    out.i32(static_cast<std::int64_t>(m.voxels));
    if (m.voxels == 0) continue;
    for (std::int64_t z = 0; z < m.size.z; ++z) {
      for (std::int64_t y = 0; y < m.size.y; ++y) {
        const Rgba8* row = &volume.at(m.corner.x, m.corner.y + y, m.corner.z + z);
        for (std::int64_t x = 0; x < m.size.x; ++x) {
          if (row[x].a == 0) continue;
          out.u8(static_cast<std::uint8_t>(x));
          out.u8(static_cast<std::uint8_t>(y));
          out.u8(static_cast<std::uint8_t>(z));
          out.u8(index_of(row[x]));
        }
      }
      out.maybe_flush();
    }
  }
  out.bytes(scene);
  out.chunk("RGBA", 4 * 256, 0);
  for (std::size_t p = 0; p < 256; ++p) {
    const Rgba8 c = p < palette.size() ? palette[p] : Rgba8{};
    out.u8(c.r);
    out.u8(c.g);
    out.u8(c.b);
    out.u8(c.a);
  }
  out.flush();
}

}  // namespace voxd
