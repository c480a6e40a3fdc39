// Memory for volumes (voxd/volume_memory.h): heap blocks for small volumes,
// OS pages for large ones; zeroed when asked, writable to the last byte, and
// dense volumes built on it behave as vectors do.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cerrno>
#include <cstring>

#include <sys/mman.h>

#include <vector>

#include <gtest/gtest.h>

#include "voxd/bit_volume.h"
#include "voxd/dense_volume.h"
#include "voxd/volume_memory.h"

namespace voxd {
namespace {

TEST(VolumeMemory, SmallAndLargeBlocksAreZeroedWhenAskedAndWritableToTheEnd) {
  // Below the heap limit, at it, and a multi-page block past the huge-page size.
  for (const std::size_t bytes : {std::size_t{1}, std::size_t{4096}, std::size_t{1} << 20, (std::size_t{9} << 20) + 3}) {
    auto* p = static_cast<std::uint8_t*>(allocate_volume_memory(bytes, true));
    ASSERT_NE(p, nullptr);
    EXPECT_TRUE(std::all_of(p, p + bytes, [](std::uint8_t b) { return b == 0; })) << bytes;
    std::memset(p, 0xab, bytes);
    EXPECT_EQ(p[bytes - 1], 0xab);
    free_volume_memory(p, bytes);
  }
  free_volume_memory(nullptr, 1 << 20);  // a no-op, as free(nullptr)
}

TEST(VolumeMemory, LargeBlocksAreReusedForTheSameSizeAndZeroedWhenAsked) {
  const std::size_t bytes = std::size_t{80} << 20;
  auto* a = static_cast<std::uint8_t*>(allocate_volume_memory(bytes, false));
  std::memset(a, 0xcd, bytes);
  free_volume_memory(a, bytes);
  // The same size gets the kept block back, cleared when asked.
  auto* b = static_cast<std::uint8_t*>(allocate_volume_memory(bytes, true));
  EXPECT_EQ(b, a);
  EXPECT_TRUE(std::all_of(b, b + bytes, [](std::uint8_t x) { return x == 0; }));
  std::memset(b, 0xef, bytes);
  free_volume_memory(b, bytes);
  auto* c = static_cast<std::uint8_t*>(allocate_volume_memory(bytes, false));
  EXPECT_EQ(c, a);
  EXPECT_EQ(c[bytes - 1], 0xef);  // not cleared when not asked: the caller fills it
  free_volume_memory(c, bytes);
  // Another size maps fresh (zero) pages.
  const std::size_t other = bytes + 4096;
  auto* d = static_cast<std::uint8_t*>(allocate_volume_memory(other, true));
  EXPECT_TRUE(std::all_of(d, d + other, [](std::uint8_t x) { return x == 0; }));
  free_volume_memory(d, other);
  // A float volume built on a reused block holds its fill everywhere.
  const Grid g{glm::dvec3(0.0), 1.0, glm::i64vec3(512, 256, 160)};  // 80 MiB of floats
  { DenseVolume<float> first(g, -7.0f); }
  const DenseVolume<float> second(g, 2.5f);
  EXPECT_TRUE(std::all_of(second.values().begin(), second.values().end(), [](float v) { return v == 2.5f; }));
}

// A report frees its 4-byte feature transform before it makes its 2-byte
// peel depths: the smaller volume takes the kept block's first pages, as
// they are (or cleared when asked), and the tail goes back to the OS.
TEST(VolumeMemory, ASmallerVolumeTakesAKeptLargerBlocksPages) {
  const std::size_t bytes = std::size_t{96} << 20, smaller = (std::size_t{70} << 20) + 123;
  auto* a = static_cast<std::uint8_t*>(allocate_volume_memory(bytes, false));
  std::memset(a, 0x5a, bytes);
  free_volume_memory(a, bytes);
  auto* b = static_cast<std::uint8_t*>(allocate_volume_memory(smaller, false));
  EXPECT_EQ(b, a);
  EXPECT_TRUE(std::all_of(b, b + smaller, [](std::uint8_t x) { return x == 0x5a; }));  // not cleared: not asked
  // The tail past the smaller size's last page is unmapped.
  const std::size_t page = 4096, tail = (smaller + page - 1) / page * page;
  unsigned char resident = 0;
  EXPECT_EQ(::mincore(a + tail, page, &resident), -1);
  EXPECT_EQ(errno, ENOMEM);
  std::memset(b, 0x11, smaller);
  free_volume_memory(b, smaller);
  // Asked zeroed, a smaller size still reads zeros.
  auto* c = static_cast<std::uint8_t*>(allocate_volume_memory(smaller - 4096, true));
  EXPECT_EQ(c, a);
  EXPECT_TRUE(std::all_of(c, c + smaller - 4096, [](std::uint8_t x) { return x == 0; }));
  free_volume_memory(c, smaller - 4096);
}

TEST(VolumeMemory, DenseVolumesFillCopyAndCompareAsVectors) {
  // 24 MiB of floats: on OS pages.
  const Grid g{glm::dvec3(0.0), 1.0, glm::i64vec3(256, 256, 96)};
  DenseVolume<float> a(g, 1.5f);
  ASSERT_EQ(a.values().size(), g.voxel_count());
  EXPECT_TRUE(std::all_of(a.values().begin(), a.values().end(), [](float v) { return v == 1.5f; }));
  DenseVolume<float> b = a;  // a copy owns its own pages
  b.at(255, 255, 95) = -2.0f;
  EXPECT_EQ(a.at(255, 255, 95), 1.5f);
  EXPECT_FALSE(a.values() == b.values());
  b.at(255, 255, 95) = 1.5f;
  EXPECT_TRUE(a.values() == b.values());
  DenseVolume<float> moved = std::move(b);
  EXPECT_EQ(moved.at(0, 0, 0), 1.5f);
  // Small volumes (the heap) too.
  DenseVolume<std::uint8_t> small(Grid{glm::dvec3(0.0), 1.0, glm::i64vec3(3, 2, 1)}, 7);
  EXPECT_EQ(small.values(), (VolumeVector<std::uint8_t>{7, 7, 7, 7, 7, 7}));
  // A bit volume larger than the heap limit starts empty.
  const BitVolume bits(Grid{glm::dvec3(0.0), 1.0, glm::i64vec3(1024, 1024, 16)});
  EXPECT_EQ(bits.count(), 0u);
}

// A dense volume of zeros asks for zeroed memory rather than writing it:
// on a reused block (which held another volume) it is zero everywhere, on
// the heap too, and on fresh pages nothing is written (they stay unmapped
// until a writer touches them: mincore says which pages are resident). Any
// other fill, -0.0 included, is written.
TEST(VolumeMemory, ZeroFilledDenseVolumesAreZeroWithoutBeingWritten) {
  const Grid g{glm::dvec3(0.0), 1.0, glm::i64vec3(512, 256, 176)};  // 88 MiB of floats: OS pages
  { DenseVolume<float> first(g, 3.0f); }
  const DenseVolume<float> reused(g);  // the kept block of `first`
  EXPECT_TRUE(std::all_of(reused.values().begin(), reused.values().end(), [](float v) { return v == 0.0f; }));
  const DenseVolume<std::uint16_t> small(Grid{glm::dvec3(0.0), 1.0, glm::i64vec3(7, 5, 3)});
  EXPECT_EQ(small.values(), VolumeVector<std::uint16_t>(105, 0));

  const Grid other{glm::dvec3(0.0), 1.0, glm::i64vec3(512, 256, 184)};  // a size nothing kept
  DenseVolume<std::uint32_t> fresh(other);
  const std::size_t bytes = fresh.values().size() * sizeof(std::uint32_t);
  std::vector<unsigned char> pages((bytes + 4095) / 4096);
  ASSERT_EQ(::mincore(fresh.values().data(), bytes, pages.data()), 0);
  const auto resident = std::count_if(pages.begin(), pages.end(), [](unsigned char c) { return c & 1; });
  EXPECT_LT(resident, static_cast<std::ptrdiff_t>(pages.size() / 10)) << "the zero volume was written";
  EXPECT_TRUE(std::all_of(fresh.values().begin(), fresh.values().end(), [](std::uint32_t v) { return v == 0; }));

  const DenseVolume<float> negative_zero(Grid{glm::dvec3(0.0), 1.0, glm::i64vec3(64, 64, 64)}, -0.0f);
  EXPECT_TRUE(std::all_of(negative_zero.values().begin(), negative_zero.values().end(),
                          [](float v) { return std::signbit(v); }));
  const DenseVolume<float> copy = reused;  // a copy holds the same values
  EXPECT_TRUE(copy.values() == reused.values());
}

// A volume made Uninitialized (to be read into) writes and clears nothing:
// on a reused block it holds the last volume's values, on fresh pages it
// leaves them untouched.
TEST(VolumeMemory, AnUninitializedDenseVolumeTouchesNothing) {
  const Grid g{glm::dvec3(0.0), 1.0, glm::i64vec3(512, 256, 168)};  // 84 MiB of floats
  { DenseVolume<float> first(g, 6.5f); }
  const DenseVolume<float> reused(g, DenseVolume<float>::Uninitialized{});
  EXPECT_EQ(reused.values().size(), g.voxel_count());
  EXPECT_EQ(reused.at(511, 255, 167), 6.5f);  // the kept block, as it was
  // With no kept block to take (earlier tests' larger ones would serve it),
  // a new mapping: nothing of it is faulted in.
  set_keep_freed_volumes(false);
  set_keep_freed_volumes(true);
  const Grid other{glm::dvec3(0.0), 1.0, glm::i64vec3(512, 256, 172)};
  const DenseVolume<float> fresh(other, DenseVolume<float>::Uninitialized{});
  const std::size_t bytes = fresh.values().size() * sizeof(float);
  std::vector<unsigned char> pages((bytes + 4095) / 4096);
  ASSERT_EQ(::mincore(const_cast<float*>(fresh.values().data()), bytes, pages.data()), 0);
  EXPECT_LT(std::count_if(pages.begin(), pages.end(), [](unsigned char c) { return c & 1; }),
            static_cast<std::ptrdiff_t>(pages.size() / 10));
}

// A host that shares its memory turns keeping off: freed blocks then go back
// to the OS at once, and so do those kept when it turns it off. mincore()
// fails with ENOMEM on pages no longer mapped.
TEST(VolumeMemory, AHostCanHaveFreedBlocksReturnedAtOnce) {
  const std::size_t bytes = std::size_t{96} << 20;
  auto mapped = [](void* p, std::size_t n) {
    std::vector<unsigned char> pages((n + 4095) / 4096);
    return ::mincore(p, n, pages.data()) == 0;
  };
  ASSERT_TRUE(keeps_freed_volumes());
  void* a = allocate_volume_memory(bytes, false);
  std::memset(a, 1, bytes);
  free_volume_memory(a, bytes);
  EXPECT_TRUE(mapped(a, bytes));  // kept for the next volume of its size
  set_keep_freed_volumes(false);
  EXPECT_FALSE(keeps_freed_volumes());
  EXPECT_FALSE(mapped(a, bytes));  // what was kept went back
  void* b = allocate_volume_memory(bytes, false);
  std::memset(b, 2, bytes);
  free_volume_memory(b, bytes);
  EXPECT_FALSE(mapped(b, bytes));
  set_keep_freed_volumes(true);
  void* c = allocate_volume_memory(bytes, false);
  free_volume_memory(c, bytes);
  EXPECT_TRUE(mapped(c, bytes));
}

}  // namespace
}  // namespace voxd
