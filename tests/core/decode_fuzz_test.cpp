// Randomized robustness test for the decoders: thousands of mutated valid
// files (bit flips, truncations, insertions, corrupted header counts) and
// random inputs go through detection, decode_mesh and every decoder. Each
// call must either throw voxd::Error or return a valid mesh: indices in
// range, no repeated index, finite coordinates, at least one triangle.
// Seeds are fixed, so a failure reproduces; it prints the case to rerun.
// VOXD_FUZZ_SCALE=N runs N times as many cases, for a deeper one-off search.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/draco_cli.h"
#include "support/ply_writer.h"
#include "support/test_meshes.h"
#include "voxd/error.h"
#include "voxd/mesh_io/mesh_decode.h"

namespace voxd {
namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr MeshFormat kAllFormats[] = {MeshFormat::stl_binary, MeshFormat::stl_ascii, MeshFormat::obj,
                                      MeshFormat::ply, MeshFormat::draco};

Bytes bytes_of(const std::string& text) { return {text.begin(), text.end()}; }

int cases(int base) {
  const char* scale = std::getenv("VOXD_FUZZ_SCALE");
  return scale ? base * std::max(1, std::atoi(scale)) : base;
}

struct Seed {
  std::string name;
  Bytes bytes;
};

std::vector<Seed> make_seeds() {
  const Mesh box = test::make_box({-1, 0, 2}, {3, 0.5, 4.25});
  const Mesh ball = test::make_icosphere({0, 0, 0}, 1, 1);
  std::vector<Seed> seeds = {
      {"binary STL", test::to_binary_stl(ball)},
      {"binary STL, solid header", test::to_binary_stl(box, "solid box")},
      {"ASCII STL", bytes_of(test::to_ascii_stl(box))},
      {"OBJ", bytes_of("# box\nv 0 0 0\nv 2 0 0\nv 0 3 0\nv 2 3 0\nv 0 0 4\nv 2 0 4\nv 0 3 4\nv 2 3 4\nvt 0 0\n"
                       "f 1/1/1 3/2/1 4/3/1 2/4/1\nf -4//1 -3//1 -1//1 -2//1\nf 1/1 2/2 6/3 5/4\nf 3 7 8 4\n"
                       "f -8/1/1 -4/2/1 -2/3/1 -6/4/1\nf 2 4 8 6\n")},
      {"ASCII PLY", bytes_of(test::to_ascii_ply(box))},
  };
  test::PlyOptions le;
  le.encoding = test::PlyOptions::Encoding::binary_little_endian;
  le.extra_properties = true;
  seeds.push_back({"binary LE PLY, extra properties", test::to_ply(box, le)});
  test::PlyOptions be;
  be.encoding = test::PlyOptions::Encoding::binary_big_endian;
  be.coordinate_type = "double";
  be.count_type = "ushort";
  be.index_type = "uint";
  be.quads = true;
  seeds.push_back({"binary BE PLY, doubles and quads", test::to_ply(box, be)});
  if (test::draco_encoder_available()) {
    seeds.push_back({"Draco", test::encode_with_draco_encoder(ball, "")});
    seeds.push_back({"Draco, high precision", test::encode_with_draco_encoder(box, "-qp 20 -cl 10")});
  }
  return seeds;
}

const std::vector<Seed>& seeds() {
  static const std::vector<Seed> all = make_seeds();
  return all;
}

std::string describe(const Bytes& data) {
  std::string out = std::to_string(data.size()) + " bytes:";
  char hex[4];
  for (std::size_t i = 0; i < std::min<std::size_t>(data.size(), 96); ++i) {
    std::snprintf(hex, sizeof hex, " %02x", data[i]);
    out += hex;
  }
  return out + (data.size() > 96 ? " ..." : "");
}

// Empty when the mesh is valid, else what is wrong with it.
std::string problems_of(const Mesh& mesh) {
  if (mesh.triangles.empty()) return "no triangles";
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const glm::vec3& v = mesh.vertices[i];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
      return "vertex " + std::to_string(i) + " is not finite";
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (std::uint32_t v : tri)
      if (v >= mesh.vertices.size()) return "triangle " + std::to_string(t) + " index out of range";
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2])
      return "triangle " + std::to_string(t) + " repeats an index";
  }
  return {};
}

// Feeds `data` to detection, decode_mesh and every decoder.
class Harness {
 public:
  int decoded = 0, rejected = 0;

  void check(const Bytes& data, const std::string& what, const DecodeLimits& limits = {}) {
    const MeshFormat detected = detect_mesh_format(data, "upload.obj");
    (void)detected;
    run(data, what + ", decode_mesh", [&] { return decode_mesh(data, "upload", limits); });
    for (MeshFormat format : kAllFormats)
      run(data, what + ", decode_mesh_as " + to_string(format), [&] { return decode_mesh_as(format, data, limits); });
  }

 private:
  template <typename Decode>
  void run(const Bytes& data, const std::string& what, Decode decode) {
    try {
      const Mesh mesh = decode();
      const std::string problems = problems_of(mesh);
      if (!problems.empty()) ADD_FAILURE() << what << " returned an invalid mesh (" << problems << ") for " << describe(data);
      ++decoded;
    } catch (const Error&) {
      ++rejected;
    } catch (const std::exception& e) {
      ADD_FAILURE() << what << " threw a non-voxd exception '" << e.what() << "' for " << describe(data);
    }
  }
};

class Mutator {
 public:
  explicit Mutator(std::uint64_t seed) : rng_(seed) {}

  std::size_t below(std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(rng_() % n); }
  bool chance(int percent) { return below(100) < static_cast<std::size_t>(percent); }
  std::uint8_t byte() { return static_cast<std::uint8_t>(rng_()); }

  // Applies 1 to 3 random mutations; returns their names.
  std::string mutate(Bytes& data, const std::vector<Seed>& others) {
    std::string names;
    const std::size_t count = 1 + below(3);
    for (std::size_t i = 0; i < count; ++i) {
      switch (below(8)) {
        case 0: names += flip_bits(data); break;
        case 1: names += overwrite_bytes(data); break;
        case 2: names += truncate(data); break;
        case 3: names += insert_bytes(data); break;
        case 4: names += delete_range(data); break;
        case 5: names += corrupt_count(data); break;
        case 6: names += splice(data, others[below(others.size())].bytes); break;
        default: names += insert_token(data); break;
      }
    }
    return names;
  }

  std::string corrupt_count(Bytes& data) {
    const std::string text(data.begin(), data.end());
    // PLY element counts, e.g. "element vertex 8".
    const std::size_t element = text.find(chance(50) ? "element vertex " : "element face ");
    if (element != std::string::npos) {
      const std::size_t number = text.find(' ', element + 8) + 1;
      const std::size_t end = text.find('\n', number);
      if (end != std::string::npos) {
        const std::string replacement = interesting_count();
        data.erase(data.begin() + number, data.begin() + end);
        data.insert(data.begin() + number, replacement.begin(), replacement.end());
        return " ply-count=" + replacement;
      }
    }
    // The binary STL triangle count.
    if (data.size() >= 84 && !text.starts_with("ply") && !text.starts_with("DRACO")) {
      const std::uint32_t values[] = {0, 1, 0x7FFFFFFF, 0xFFFFFFFF, static_cast<std::uint32_t>((data.size() - 84) / 50 + 1),
                                      static_cast<std::uint32_t>(rng_())};
      const std::uint32_t count = values[below(std::size(values))];
      std::memcpy(data.data() + 80, &count, 4);
      return " stl-count=" + std::to_string(count);
    }
    return overwrite_bytes(data);
  }

 private:
  std::string interesting_count() {
    static const char* counts[] = {"0", "1", "2", "-1", "255", "65536", "2147483648", "4000000000", "4294967296",
                                   "18446744073709551615", "9223372036854775807", "99999999999999999999", "1e3", "x"};
    return chance(80) ? counts[below(std::size(counts))] : std::to_string(rng_());
  }

  std::string flip_bits(Bytes& data) {
    if (data.empty()) return " flip(empty)";
    const std::size_t flips = 1 + below(8);
    for (std::size_t i = 0; i < flips; ++i) data[below(data.size())] ^= static_cast<std::uint8_t>(1u << below(8));
    return " flip" + std::to_string(flips);
  }

  std::string overwrite_bytes(Bytes& data) {
    static const std::uint8_t interesting[] = {0, 0xFF, 0x7F, 0x80, '\n', '\r', ' ', '-', '0', '9', 'e', '.', '/', '#'};
    if (data.empty()) return " overwrite(empty)";
    const std::size_t n = 1 + below(4);
    for (std::size_t i = 0; i < n; ++i)
      data[below(data.size())] = chance(50) ? interesting[below(std::size(interesting))] : byte();
    return " overwrite" + std::to_string(n);
  }

  std::string truncate(Bytes& data) {
    data.resize(below(data.size()));
    return " truncate@" + std::to_string(data.size());
  }

  std::string insert_bytes(Bytes& data) {
    const std::size_t at = below(data.size() + 1), n = 1 + below(16);
    Bytes extra(n);
    for (auto& b : extra) b = byte();
    data.insert(data.begin() + static_cast<std::ptrdiff_t>(at), extra.begin(), extra.end());
    return " insert" + std::to_string(n) + "@" + std::to_string(at);
  }

  std::string insert_token(Bytes& data) {
    static const char* tokens[] = {"nan", "-inf", "1e39", "-1", "0", "4294967295", "999999999999", "\n", "\r",
                                   " ", "end_header\n", "f 1 2 3\n", "v 1 2 3\n", "facet", "vertex", "endsolid\n",
                                   "solid", "element face 3\n", "property list uchar int vertex_indices\n", "/", "//"};
    const std::string token = tokens[below(std::size(tokens))];
    const std::size_t at = below(data.size() + 1);
    data.insert(data.begin() + static_cast<std::ptrdiff_t>(at), token.begin(), token.end());
    return " token@" + std::to_string(at);
  }

  std::string delete_range(Bytes& data) {
    if (data.empty()) return " delete(empty)";
    const std::size_t at = below(data.size()), n = 1 + below(std::min<std::size_t>(64, data.size() - at));
    data.erase(data.begin() + static_cast<std::ptrdiff_t>(at), data.begin() + static_cast<std::ptrdiff_t>(at + n));
    return " delete" + std::to_string(n) + "@" + std::to_string(at);
  }

  std::string splice(Bytes& data, const Bytes& other) {
    const std::size_t keep = below(data.size() + 1), from = below(other.size() + 1);
    data.resize(keep);
    data.insert(data.end(), other.begin() + static_cast<std::ptrdiff_t>(from), other.end());
    return " splice@" + std::to_string(keep);
  }

  std::mt19937_64 rng_;
};

TEST(DecodeFuzz, SeedsThemselvesDecode) {
  for (const Seed& seed : seeds()) {
    SCOPED_TRACE(seed.name);
    const Mesh mesh = decode_mesh(seed.bytes);
    EXPECT_EQ(problems_of(mesh), "");
  }
  if (!test::draco_encoder_available())
    std::fprintf(stderr, "note: %s missing, Draco is fuzzed from random data only\n", test::kDracoEncoder);
}

TEST(DecodeFuzz, MutatedFilesOfEveryFormat) {
  const int mutants_per_seed = cases(4000);
  Harness harness;
  for (std::size_t s = 0; s < seeds().size(); ++s) {
    const Seed& seed = seeds()[s];
    Mutator mutator(0x5EED0000 + s);
    for (int i = 0; i < mutants_per_seed; ++i) {
      Bytes data = seed.bytes;
      const std::string mutations = mutator.mutate(data, seeds());
      harness.check(data, seed.name + " #" + std::to_string(i) + mutations);
      if (testing::Test::HasFailure()) return;  // one reproducible case is enough
    }
  }
  RecordProperty("decoded", harness.decoded);
  RecordProperty("rejected", harness.rejected);
  // Mutants must exercise both outcomes, or the test proves little.
  EXPECT_GT(harness.decoded, 3000);
  EXPECT_GT(harness.rejected, 30000);
}

TEST(DecodeFuzz, CorruptedHeaderCounts) {
  // Counts that promise far more (or less) than the data holds, with small
  // limits too, so the limit checks race the size checks.
  DecodeLimits small;
  small.max_triangles = 16;
  small.max_bytes = 1 << 16;
  Harness harness;
  for (std::size_t s = 0; s < seeds().size(); ++s) {
    const Seed& seed = seeds()[s];
    Mutator mutator(0xC0C0 + s);
    for (int i = 0; i < cases(1000); ++i) {
      Bytes data = seed.bytes;
      const std::string mutation = mutator.corrupt_count(data);
      harness.check(data, seed.name + " #" + std::to_string(i) + mutation, i % 2 ? small : DecodeLimits{});
      if (testing::Test::HasFailure()) return;
    }
  }
  EXPECT_GT(harness.rejected, 1000);
}

TEST(DecodeFuzz, RandomBytesAndMagicPrefixes) {
  static const char* prefixes[] = {"", "DRACO", "DRACO\x02\x02\x01\x01", "ply\n", "ply\nformat binary_little_endian 1.0\n",
                                   "solid x\n", "v ", "# c\n"};
  std::mt19937_64 rng(0xB17E5);
  Harness harness;
  for (int i = 0; i < cases(8000); ++i) {
    const std::string prefix = prefixes[i % std::size(prefixes)];
    Bytes data(prefix.begin(), prefix.end());
    const std::size_t n = rng() % (i % 10 == 0 ? 2000 : 200);
    for (std::size_t k = 0; k < n; ++k) data.push_back(static_cast<std::uint8_t>(rng()));
    harness.check(data, "random #" + std::to_string(i));
    if (testing::Test::HasFailure()) return;
  }
}

TEST(DecodeFuzz, RandomTokenSoup) {
  // Syntactically plausible text: keywords and numbers of every format in
  // random order, which reaches deeper into the text parsers than bytes do.
  static const char* tokens[] = {
      "solid", "facet", "normal", "outer", "loop", "vertex", "endloop", "endfacet", "endsolid", "v", "vt", "f",
      "ply", "format", "ascii", "binary_little_endian", "binary_big_endian", "1.0", "element", "face",
      "property", "list", "uchar", "int", "float", "double", "x", "y", "z", "vertex_indices", "end_header",
      "0", "1", "2", "3", "-1", "-2", "4", "7", "0.5", "-2.5e3", "nan", "inf", "1e39", "1/2/3", "2//1", "#"};
  static const char* separators[] = {" ", " ", " ", "\n", "\r\n", "\t", "\r"};
  std::mt19937_64 rng(0x70C3);
  Harness harness;
  for (int i = 0; i < cases(8000); ++i) {
    std::string text;
    // Start like a real file half the time, so the parsers get past line 1.
    static const char* starts[] = {"solid t\n", "ply\nformat ascii 1.0\n", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", ""};
    text += starts[rng() % std::size(starts)];
    const std::size_t n = rng() % 120;
    for (std::size_t k = 0; k < n; ++k) {
      text += tokens[rng() % std::size(tokens)];
      text += separators[rng() % std::size(separators)];
    }
    harness.check(bytes_of(text), "tokens #" + std::to_string(i));
    if (testing::Test::HasFailure()) return;
  }
  EXPECT_GT(harness.rejected, 10000);
}

}  // namespace
}  // namespace voxd
