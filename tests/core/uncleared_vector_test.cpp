// Memory written and given back on every thread (voxd/uncleared_vector.h):
// which bytes a page release drops, and that a freed vector or run slab
// holds nothing after.
#include "voxd/uncleared_vector.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <vector>

#include "voxd/run_slab.h"

namespace voxd {
namespace {

TEST(ReleasePages, DropsTheWholePagesInsideTheRangeAndNothingElse) {
  const auto page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  for (const int threads : {1, 4}) {
    UnclearedVector<std::uint8_t> v;
    assign_on_every_thread(v, std::size_t{13} << 20, std::uint8_t{0xAB}, 2);
    // A range that starts and ends inside pages: those two keep their bytes.
    const std::size_t from = 3 * page + 123, to = v.size() - 2 * page - 77;
    release_pages_on_every_thread(v.data() + from, to - from, threads);
    const auto at = reinterpret_cast<std::uintptr_t>(v.data());
    const std::uintptr_t first = (at + from + page - 1) / page * page, last = (at + to) / page * page;
    std::size_t dropped = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
      const std::uintptr_t p = at + i;
      const bool whole_page_inside = p >= first && p < last;
      ASSERT_EQ(v[i], whole_page_inside ? 0 : 0xAB) << "byte " << i << ", " << threads << " threads";
      dropped += whole_page_inside;
    }
    EXPECT_GE(dropped, (to - from) - 2 * page);
  }
}

TEST(ReleasePages, LeavesARangeWithinOnePageAlone) {
  const auto page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  UnclearedVector<std::uint8_t> v(4 * page, 0x5C);
  const auto at = reinterpret_cast<std::uintptr_t>(v.data());
  const std::size_t into = (at + page - 1) / page * page - at + 1;  // one byte into the first whole page
  release_pages_on_every_thread(v.data() + into, page - 2, 2);
  for (const std::uint8_t b : v) ASSERT_EQ(b, 0x5C);
}

TEST(FreeOnEveryThread, LeavesTheVectorWithoutMemory) {
  UnclearedVector<std::uint32_t> v;
  assign_on_every_thread(v, std::size_t{5} << 20, std::uint32_t{7}, 2);
  free_on_every_thread(v, 4);
  EXPECT_TRUE(v.empty());
  EXPECT_EQ(v.capacity(), 0u);
  // Usable again, as any emptied vector.
  v.assign(3, 9u);
  EXPECT_EQ(v, (UnclearedVector<std::uint32_t>{9, 9, 9}));
  std::vector<double> plain(std::size_t{3} << 20, 1.5);  // and an ordinary vector, on one thread
  free_on_every_thread(plain, 1);
  EXPECT_EQ(plain.capacity(), 0u);
}

TEST(FreeOnEveryThread, LeavesARunSlabEmptyAndReusable) {
  Grid grid;
  grid.dims = {4096, 512, 2};
  RunSlab slab(grid);
  slab.reserve_runs(std::size_t{4} << 20);  // 32 MiB of bounds, enough to be released in pieces
  for (std::int64_t r = 0; r < grid.dims.y * grid.dims.z; ++r) {
    slab.add_run(1, 3);
    slab.add_run(10, 4000);
    slab.end_row();
  }
  ASSERT_EQ(slab.run_count(), 2u * 512 * 2);
  slab.free_on_every_thread(4);
  EXPECT_EQ(slab.run_count(), 0u);
  EXPECT_EQ(slab.count(), 0u);
  EXPECT_EQ(slab.row_count(), 0);
  grid.dims.z = 1;
  slab.reset(grid);
  slab.add_run(5, 6);
  for (std::int64_t j = 0; j < grid.dims.y; ++j) slab.end_row();
  EXPECT_EQ(slab.count(), 1u);
  EXPECT_EQ(slab.row(0, 0).size(), 2u);
  EXPECT_EQ(slab.row(1, 0).size(), 0u);
}

}  // namespace
}  // namespace voxd
