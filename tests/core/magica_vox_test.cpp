// MagicaVoxel .vox output, read back by a parser written here from the
// format's documents (chunk walk, scene graph, palette) rather than by
// anything the writer shares, so the tests check what a viewer reads.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_checks.h"
#include "voxd/error.h"
#include "voxd/encode/magica_vox.h"

namespace voxd {
namespace {

using test::code_of;

// ------------------------------------------------------------- parser --

struct Chunk {
  std::string id;
  std::vector<std::uint8_t> content;
  std::vector<Chunk> children;
};

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : p_(data), end_(data + size) {}
  bool done() const { return p_ == end_; }
  std::size_t left() const { return static_cast<std::size_t>(end_ - p_); }
  std::int32_t i32() {
    need(4);
    std::uint32_t v = 0;
    for (int b = 0; b < 4; ++b) v |= std::uint32_t{p_[b]} << (8 * b);
    p_ += 4;
    return static_cast<std::int32_t>(v);
  }
  std::uint8_t u8() {
    need(1);
    return *p_++;
  }
  std::string text(std::size_t n) {
    need(n);
    std::string s(reinterpret_cast<const char*>(p_), n);
    p_ += n;
    return s;
  }
  std::string string() {
    const std::int32_t n = i32();
    if (n < 0) throw std::runtime_error("negative string length");
    return text(static_cast<std::size_t>(n));
  }
  std::map<std::string, std::string> dict() {
    const std::int32_t n = i32();
    std::map<std::string, std::string> d;
    for (std::int32_t i = 0; i < n; ++i) {
      std::string key = string();
      d[key] = string();
    }
    return d;
  }
  std::vector<std::uint8_t> bytes(std::size_t n) {
    need(n);
    std::vector<std::uint8_t> b(p_, p_ + n);
    p_ += n;
    return b;
  }

 private:
  void need(std::size_t n) const {
    if (left() < n) throw std::runtime_error("truncated");
  }
  const std::uint8_t* p_;
  const std::uint8_t* end_;
};

Chunk read_chunk(Reader& in) {
  Chunk c;
  c.id = in.text(4);
  const std::int32_t n = in.i32();
  const std::int32_t m = in.i32();
  if (n < 0 || m < 0) throw std::runtime_error("negative chunk size in " + c.id);
  c.content = in.bytes(static_cast<std::size_t>(n));
  std::vector<std::uint8_t> children = in.bytes(static_cast<std::size_t>(m));
  Reader sub(children.data(), children.size());
  while (!sub.done()) c.children.push_back(read_chunk(sub));
  return c;
}

struct VoxModel {
  std::array<int, 3> size{};
  std::vector<std::array<std::uint8_t, 4>> voxels;  // x, y, z, colour index
};

struct VoxFile {
  Chunk main;
  std::vector<VoxModel> models;
  std::array<Rgba8, 256> rgba{};               // RGBA chunk positions 0..255
  std::vector<std::array<long, 3>> placement;  // per model: summed _t of the nTRN path to it
  std::vector<int> model_refs;                 // per model: how many nSHP reference it
};

std::array<long, 3> parse_t(const std::string& t) {
  std::istringstream s(t);
  std::array<long, 3> v{};
  s >> v[0] >> v[1] >> v[2];
  if (!s) throw std::runtime_error("bad _t \"" + t + "\"");
  return v;
}

VoxFile parse_vox(const std::vector<std::uint8_t>& bytes) {
  Reader in(bytes.data(), bytes.size());
  if (in.text(4) != "VOX ") throw std::runtime_error("no VOX magic");
  if (in.i32() != 150) throw std::runtime_error("not version 150");
  VoxFile f;
  f.main = read_chunk(in);
  if (!in.done()) throw std::runtime_error("bytes after MAIN");
  if (f.main.id != "MAIN" || !f.main.content.empty()) throw std::runtime_error("bad MAIN");

  std::map<int, Chunk> nodes;
  bool have_rgba = false;
  for (std::size_t i = 0; i < f.main.children.size(); ++i) {
    const Chunk& c = f.main.children[i];
    Reader r(c.content.data(), c.content.size());
    if (c.id == "SIZE") {
      VoxModel m;
      for (int& s : m.size) s = r.i32();
      if (i + 1 >= f.main.children.size() || f.main.children[i + 1].id != "XYZI")
        throw std::runtime_error("SIZE without XYZI");
      const Chunk& xyzi = f.main.children[++i];
      Reader v(xyzi.content.data(), xyzi.content.size());
      const std::int32_t n = v.i32();
      for (std::int32_t k = 0; k < n; ++k) m.voxels.push_back({v.u8(), v.u8(), v.u8(), v.u8()});
      if (!v.done()) throw std::runtime_error("XYZI size mismatch");
      f.models.push_back(std::move(m));
    } else if (c.id == "RGBA") {
      if (c.content.size() != 1024) throw std::runtime_error("RGBA chunk not 1024 bytes");
      for (std::size_t p = 0; p < 256; ++p)
        f.rgba[p] = Rgba8{c.content[4 * p], c.content[4 * p + 1], c.content[4 * p + 2], c.content[4 * p + 3]};
      have_rgba = true;
    } else if (c.id == "nTRN" || c.id == "nGRP" || c.id == "nSHP") {
      const int id = r.i32();
      if (!nodes.emplace(id, c).second) throw std::runtime_error("duplicate node id");
    }
    if (!r.done() && c.id == "SIZE") throw std::runtime_error("SIZE size mismatch");
  }
  if (!have_rgba) throw std::runtime_error("no RGBA chunk");

  // Scene graph walk from the root transform, translations summed.
  f.placement.assign(f.models.size(), {0, 0, 0});
  f.model_refs.assign(f.models.size(), 0);
  std::function<void(int, std::array<long, 3>, int)> walk = [&](int id, std::array<long, 3> t, int depth) {
    if (depth > 64) throw std::runtime_error("scene graph too deep");
    const auto it = nodes.find(id);
    if (it == nodes.end()) throw std::runtime_error("missing node " + std::to_string(id));
    const Chunk& c = it->second;
    Reader r(c.content.data(), c.content.size());
    r.i32();
    r.dict();
    if (c.id == "nTRN") {
      const int child = r.i32();
      if (r.i32() != -1) throw std::runtime_error("nTRN reserved id not -1");
      r.i32();  // layer
      if (r.i32() != 1) throw std::runtime_error("nTRN frames not 1");
      const auto frame = r.dict();
      if (frame.count("_r")) throw std::runtime_error("unexpected rotation");
      if (frame.count("_t")) {
        const auto d = parse_t(frame.at("_t"));
        for (int a = 0; a < 3; ++a) t[a] += d[a];
      }
      walk(child, t, depth + 1);
    } else if (c.id == "nGRP") {
      const int n = r.i32();
      for (int k = 0; k < n; ++k) walk(r.i32(), t, depth + 1);
    } else {
      if (r.i32() != 1) throw std::runtime_error("nSHP must have one model");
      const int model = r.i32();
      r.dict();
      if (model < 0 || static_cast<std::size_t>(model) >= f.models.size()) throw std::runtime_error("bad model id");
      ++f.model_refs[static_cast<std::size_t>(model)];
      f.placement[static_cast<std::size_t>(model)] = t;
    }
    if (!r.done()) throw std::runtime_error(c.id + " has trailing bytes");
  };
  walk(0, {0, 0, 0}, 0);
  return f;
}

std::vector<std::uint8_t> vox_of(const DenseVolume<Rgba8>& v) {
  VectorSink sink;
  write_vox(v, sink);
  return sink.data;
}

struct Placed {
  std::array<long, 3> at;
  std::uint8_t index;
};

// Every voxel of every model at its scene position: MagicaVoxel places
// local voxel v of a size-s model at _t + v - floor(s / 2).
std::vector<Placed> placed_voxels(const VoxFile& f) {
  std::vector<Placed> out;
  for (std::size_t m = 0; m < f.models.size(); ++m) {
    const VoxModel& model = f.models[m];
    for (const auto& v : model.voxels) {
      Placed p;
      for (int a = 0; a < 3; ++a) {
        EXPECT_LT(v[a], model.size[a]) << "voxel outside its model";
        p.at[a] = f.placement[m][a] + v[a] - model.size[a] / 2;
      }
      p.index = v[3];
      out.push_back(p);
    }
  }
  return out;
}

// Checks that the file holds exactly the volume's filled voxels, once each,
// at their grid positions; returns the colour index of each filled voxel
// (by volume index).
std::map<std::size_t, std::uint8_t> check_voxels(const DenseVolume<Rgba8>& vol, const VoxFile& f) {
  const Grid& g = vol.grid();
  std::map<std::size_t, std::uint8_t> index_of;
  for (const Placed& p : placed_voxels(f)) {
    const bool inside = p.at[0] >= 0 && p.at[0] < g.dims.x && p.at[1] >= 0 && p.at[1] < g.dims.y && p.at[2] >= 0 &&
                        p.at[2] < g.dims.z;
    EXPECT_TRUE(inside) << p.at[0] << " " << p.at[1] << " " << p.at[2];
    if (!inside) continue;
    const std::size_t idx = vol.index(p.at[0], p.at[1], p.at[2]);
    EXPECT_NE(vol.values()[idx].a, 0) << "empty voxel written at " << p.at[0] << " " << p.at[1] << " " << p.at[2];
    EXPECT_GE(p.index, 1);
    EXPECT_TRUE(index_of.emplace(idx, p.index).second) << "voxel written twice";
  }
  std::size_t filled = 0;
  for (const Rgba8& c : vol.values()) filled += c.a != 0;
  EXPECT_EQ(index_of.size(), filled);
  return index_of;
}

Grid grid_of_dims(std::int64_t x, std::int64_t y, std::int64_t z) {
  Grid g;
  g.origin = {-1.5, 2.0, 0.25};
  g.voxel_size = 0.5;
  g.dims = {x, y, z};
  return g;
}

// A few colours, some voxels empty, colours in an order that is not sorted.
DenseVolume<Rgba8> patterned(std::int64_t x, std::int64_t y, std::int64_t z) {
  DenseVolume<Rgba8> v(grid_of_dims(x, y, z));
  for (std::int64_t k = 0; k < z; ++k)
    for (std::int64_t j = 0; j < y; ++j)
      for (std::int64_t i = 0; i < x; ++i) {
        const std::int64_t h = (i * 7 + j * 3 + k * 5) % 11;
        if (h == 0 || h == 4) continue;
        v.at(i, j, k) = Rgba8{static_cast<std::uint8_t>(250 - 20 * h), static_cast<std::uint8_t>(h * 13),
                              static_cast<std::uint8_t>((i / 50) * 40), static_cast<std::uint8_t>(h == 7 ? 128 : 255)};
      }
  return v;
}

// ---------------------------------------------------------------- tests --

TEST(MagicaVox, ChunkStructure) {
  const auto bytes = vox_of(patterned(300, 20, 10));
  ASSERT_GE(bytes.size(), 20u);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + 4), "VOX ");
  const VoxFile f = parse_vox(bytes);
  std::vector<std::string> ids;
  for (const Chunk& c : f.main.children) {
    ids.push_back(c.id);
    EXPECT_TRUE(c.children.empty()) << c.id;
  }
  const std::vector<std::string> expected = {"SIZE", "XYZI", "SIZE", "XYZI", "nTRN", "nGRP", "nTRN", "nSHP",
                                             "nTRN", "nSHP", "LAYR", "RGBA"};
  EXPECT_EQ(ids, expected);
  // The root transform has no translation and belongs to no layer; the
  // model transforms sit on layer 0, which the LAYR chunk declares.
  Reader root(f.main.children[4].content.data(), f.main.children[4].content.size());
  EXPECT_EQ(root.i32(), 0);
  EXPECT_TRUE(root.dict().empty());
  EXPECT_EQ(root.i32(), 1);
  EXPECT_EQ(root.i32(), -1);
  EXPECT_EQ(root.i32(), -1);
  EXPECT_EQ(root.i32(), 1);
  EXPECT_TRUE(root.dict().empty());
  Reader group(f.main.children[5].content.data(), f.main.children[5].content.size());
  EXPECT_EQ(group.i32(), 1);
  group.dict();
  EXPECT_EQ(group.i32(), 2);
  EXPECT_EQ(group.i32(), 2);
  EXPECT_EQ(group.i32(), 4);
  Reader layer(f.main.children[10].content.data(), f.main.children[10].content.size());
  EXPECT_EQ(layer.i32(), 0);
  layer.dict();
  EXPECT_EQ(layer.i32(), -1);
  EXPECT_TRUE(layer.done());
}

TEST(MagicaVox, SplitsIntoBlocksAndPlacesEveryVoxel) {
  const DenseVolume<Rgba8> vol = patterned(300, 20, 10);
  const VoxFile f = parse_vox(vox_of(vol));
  ASSERT_EQ(f.models.size(), 2u);
  EXPECT_EQ(f.models[0].size, (std::array<int, 3>{256, 20, 10}));
  EXPECT_EQ(f.models[1].size, (std::array<int, 3>{44, 20, 10}));
  EXPECT_EQ(f.model_refs, (std::vector<int>{1, 1}));
  // Centre anchored: corner + floor(size / 2).
  EXPECT_EQ(f.placement[0], (std::array<long, 3>{128, 10, 5}));
  EXPECT_EQ(f.placement[1], (std::array<long, 3>{256 + 22, 10, 5}));
  const auto index_of = check_voxels(vol, f);
  for (const auto& [idx, p] : index_of) EXPECT_EQ(f.rgba[p - 1u], vol.values()[idx]) << "voxel " << idx;
}

TEST(MagicaVox, OddSizesAndAllThreeAxesSplit) {
  // 257 x 259 x 3: blocks of 256 and 1 along x, 256 and 3 along y; odd
  // sizes test the floor in the centre anchor. Voxels only in some blocks.
  DenseVolume<Rgba8> vol(grid_of_dims(257, 259, 3));
  vol.at(0, 0, 0) = {1, 2, 3, 255};
  vol.at(256, 0, 2) = {4, 5, 6, 255};
  vol.at(256, 258, 1) = {7, 8, 9, 255};
  vol.at(100, 257, 0) = {1, 2, 3, 255};
  const VoxFile f = parse_vox(vox_of(vol));
  ASSERT_EQ(f.models.size(), 4u);
  EXPECT_EQ(f.models[0].size, (std::array<int, 3>{256, 256, 3}));
  EXPECT_EQ(f.models[1].size, (std::array<int, 3>{1, 256, 3}));
  EXPECT_EQ(f.models[2].size, (std::array<int, 3>{256, 3, 3}));
  EXPECT_EQ(f.models[3].size, (std::array<int, 3>{1, 3, 3}));
  const auto index_of = check_voxels(vol, f);
  for (const auto& [idx, p] : index_of) EXPECT_EQ(f.rgba[p - 1u], vol.values()[idx]);
}

TEST(MagicaVox, EmptyBlocksAreSkipped) {
  DenseVolume<Rgba8> vol(grid_of_dims(600, 4, 4));
  vol.at(599, 3, 3) = {10, 20, 30, 255};
  vol.at(520, 0, 1) = {10, 20, 30, 255};
  const VoxFile f = parse_vox(vox_of(vol));
  ASSERT_EQ(f.models.size(), 1u);
  EXPECT_EQ(f.models[0].size, (std::array<int, 3>{88, 4, 4}));
  EXPECT_EQ(f.models[0].voxels.size(), 2u);
  EXPECT_EQ(f.placement[0], (std::array<long, 3>{512 + 44, 2, 2}));
  check_voxels(vol, f);
}

TEST(MagicaVox, PaletteInOrderOfFirstAppearance) {
  DenseVolume<Rgba8> vol(grid_of_dims(4, 2, 2));
  const Rgba8 a{200, 0, 0, 255}, b{0, 200, 0, 255}, c{0, 0, 200, 255}, d{0, 0, 200, 100};
  vol.at(3, 1, 1) = a;  // last in x-fastest order
  vol.at(1, 0, 0) = c;
  vol.at(2, 0, 0) = b;
  vol.at(0, 1, 0) = c;
  vol.at(0, 0, 1) = d;  // same r, g, b as c: a different colour
  const VoxFile f = parse_vox(vox_of(vol));
  EXPECT_EQ(f.rgba[0], c);
  EXPECT_EQ(f.rgba[1], b);
  EXPECT_EQ(f.rgba[2], d);
  EXPECT_EQ(f.rgba[3], a);
  for (std::size_t p = 4; p < 256; ++p) EXPECT_EQ(f.rgba[p], Rgba8{}) << p;
  const auto index_of = check_voxels(vol, f);
  EXPECT_EQ(index_of.at(vol.index(3, 1, 1)), 4);
  EXPECT_EQ(index_of.at(vol.index(0, 1, 0)), 1);
}

DenseVolume<Rgba8> distinct_colours(int n, int repeat) {
  DenseVolume<Rgba8> vol(grid_of_dims(50, 20, (2 * n * repeat + 999) / 1000));
  for (int i = 0; i < n * repeat; ++i) {
    const int c = i % n;
    // A 10 x 10 x 10 lattice of spacing 28 (c < 1000), alpha varying a little.
    vol.values().at(static_cast<std::size_t>(2 * i)) =
        Rgba8{static_cast<std::uint8_t>(28 * (c % 10)), static_cast<std::uint8_t>(28 * (c / 10 % 10)),
              static_cast<std::uint8_t>(28 * (c / 100)), static_cast<std::uint8_t>(255 - c % 3)};
  }
  return vol;
}

TEST(MagicaVox, Exactly255ColoursStayExact) {
  const DenseVolume<Rgba8> vol = distinct_colours(255, 1);
  const VoxFile f = parse_vox(vox_of(vol));
  const auto index_of = check_voxels(vol, f);
  std::set<int> used;
  for (const auto& [idx, p] : index_of) {
    EXPECT_EQ(f.rgba[p - 1u], vol.values()[idx]);
    used.insert(p);
  }
  EXPECT_EQ(used.size(), 255u);
}

int distance2(Rgba8 a, Rgba8 b) {
  const int d[4] = {a.r - b.r, a.g - b.g, a.b - b.b, a.a - b.a};
  return d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3];
}

// Over 255 colours: at most 255 palette entries, each voxel on the entry
// nearest its colour (checked against every entry here), and close to it.
void check_quantized(const DenseVolume<Rgba8>& vol, int max_channel_error, double max_rms_error) {
  const auto bytes = vox_of(vol);
  const VoxFile f = parse_vox(bytes);
  const auto index_of = check_voxels(vol, f);
  std::set<int> used;
  double sum2 = 0;
  int worst = 0;
  for (const auto& [idx, p] : index_of) {
    const Rgba8 c = vol.values()[idx];
    const Rgba8 q = f.rgba[p - 1u];
    used.insert(p);
    int nearest = distance2(c, f.rgba[0]);
    for (int e = 1; e < 255; ++e) nearest = std::min(nearest, distance2(c, f.rgba[static_cast<std::size_t>(e)]));
    EXPECT_EQ(distance2(c, q), nearest) << "voxel " << idx << " not on its nearest palette entry";
    worst = std::max({worst, std::abs(c.r - q.r), std::abs(c.g - q.g), std::abs(c.b - q.b), std::abs(c.a - q.a)});
    sum2 += distance2(c, q);
  }
  EXPECT_LE(used.size(), 255u);
  EXPECT_GE(used.size(), 200u) << "the quantizer should use most of the palette";
  EXPECT_LE(worst, max_channel_error);
  EXPECT_LE(std::sqrt(sum2 / static_cast<double>(index_of.size())), max_rms_error);
  EXPECT_EQ(f.rgba[255], Rgba8{});
  for (std::size_t p = 0; p < 255; ++p) {
    if (used.count(static_cast<int>(p + 1))) {
      EXPECT_GE(f.rgba[p].a, 1) << "a used entry must be opaque enough to show";
    }
  }
  EXPECT_EQ(vox_of(vol), bytes) << "quantization must be deterministic";
}

// Bounds: 255 entries for 1000 lattice points of spacing 28 leave about 4
// points an entry, so errors of about half to one spacing are the best any
// palette can do (the writer gets 35 at worst, 21.7 rms).
TEST(MagicaVox, ThousandColoursQuantized) { check_quantized(distinct_colours(1000, 3), 42, 24.0); }

TEST(MagicaVox, TwoHundredFiftySixColoursQuantized) {
  // One colour too many for an exact palette: quantized, but nearly exact.
  check_quantized(distinct_colours(256, 1), 28, 2.0);
}

TEST(MagicaVox, GradientQuantized) {
  // Smooth gradients, every voxel a different colour: the large-volume case.
  // 255 entries over 64 x 64 x 32 levels leave boxes of about 40 levels a
  // side, errors of about 12 a channel rms (the writer gets 36 at worst,
  // 22.5 rms over r, g, b).
  DenseVolume<Rgba8> vol(grid_of_dims(64, 64, 32));
  for (std::int64_t k = 0; k < 32; ++k)
    for (std::int64_t j = 0; j < 64; ++j)
      for (std::int64_t i = 0; i < 64; ++i)
        vol.at(i, j, k) = Rgba8{static_cast<std::uint8_t>(4 * i), static_cast<std::uint8_t>(4 * j),
                                static_cast<std::uint8_t>(8 * k), 255};
  check_quantized(vol, 48, 26.0);
}

TEST(MagicaVox, EmptyVolumeIsOneEmptyModel) {
  DenseVolume<Rgba8> blank(grid_of_dims(5, 6, 7));
  blank.at(1, 1, 1) = Rgba8{9, 9, 9, 0};  // colour without alpha: still empty
  for (const DenseVolume<Rgba8>& vol : {blank, DenseVolume<Rgba8>{}}) {
    const VoxFile f = parse_vox(vox_of(vol));
    ASSERT_EQ(f.models.size(), 1u);
    EXPECT_EQ(f.models[0].size, (std::array<int, 3>{1, 1, 1}));
    EXPECT_TRUE(f.models[0].voxels.empty());
    EXPECT_EQ(f.model_refs, std::vector<int>{1});
    EXPECT_EQ(f.placement[0], (std::array<long, 3>{0, 0, 0}));
    for (const Rgba8& c : f.rgba) EXPECT_EQ(c, Rgba8{});
  }
}

TEST(MagicaVox, RefusesValuesThatDoNotMatchTheGrid) {
  DenseVolume<Rgba8> vol(grid_of_dims(3, 3, 3));
  vol.values().resize(26);
  VectorSink sink;
  EXPECT_EQ(code_of([&] { write_vox(vol, sink); }), ErrorCode::invalid_argument);
  EXPECT_TRUE(sink.data.empty());
}

TEST(MagicaVox, StreamsInPieces) {
  // A large model reaches the sink in several writes, not one.
  struct Counting final : ByteSink {
    using ByteSink::write;
    void write(std::span<const std::uint8_t> b) override {
      ++writes;
      data.insert(data.end(), b.begin(), b.end());
    }
    int writes = 0;
    std::vector<std::uint8_t> data;
  } sink;
  DenseVolume<Rgba8> vol(grid_of_dims(256, 256, 32), Rgba8{1, 2, 3, 255});
  write_vox(vol, sink);
  EXPECT_GT(sink.writes, 4);
  EXPECT_EQ(sink.data, vox_of(vol));
  const VoxFile f = parse_vox(sink.data);
  ASSERT_EQ(f.models.size(), 1u);
  EXPECT_EQ(f.models[0].voxels.size(), 256u * 256u * 32u);
}

}  // namespace
}  // namespace voxd
