// A job's thickness map is computed once and kept; the keeping (a write of
// 4 bytes a voxel and a sync) runs while the request that computed it goes
// on (server/jobs/background_save.h). These pin what that must not change:
// a second request for the map waits for the write and reads it rather than
// computing it again, and a failed write only leaves the map unkept.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <future>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "server/jobs/job_analyses.h"
#include "support/test_meshes.h"

namespace voxd::test {
namespace {

using namespace std::chrono_literals;

// A plate 4 voxels thick across a 20 x 20 x 6 grid: a wall of 4 at every
// filled voxel.
BitVolume plate() {
  BitVolume v(unit_grid(20, 20, 6));
  for (int k = 1; k <= 4; ++k)
    for (int j = 1; j <= 18; ++j)
      for (int i = 1; i <= 18; ++i) v.set(i, j, k, true);
  return v;
}

// An artifact store in memory whose writes can be held back or fail.
struct MemoryArtifacts {
  std::mutex mutex;
  std::map<std::string, std::string> kept;
  std::atomic<int> saves{0};
  std::promise<void> save_started;
  std::shared_future<void> release_saves;  // saves wait for it when set
  bool fail = false;

  server::ArtifactAccess access() {
    server::ArtifactAccess a;
    a.scope = "job-" + std::to_string(reinterpret_cast<std::uintptr_t>(this));
    a.load = [this](const std::string& key) -> std::optional<std::string> {
      std::lock_guard lock(mutex);
      auto it = kept.find(key);
      if (it == kept.end()) return std::nullopt;
      return it->second;
    };
    a.save = [this](const std::string& key, std::string_view bytes) {
      if (saves++ == 0) save_started.set_value();
      if (release_saves.valid()) release_saves.wait();
      if (fail) throw std::runtime_error("disk full");
      std::lock_guard lock(mutex);
      kept[key] = std::string(bytes);
    };
    a.load_into = [this](const std::string& key, std::span<char> out) {
      std::lock_guard lock(mutex);
      auto it = kept.find(key);
      if (it == kept.end() || it->second.size() != out.size()) return false;
      std::memcpy(out.data(), it->second.data(), out.size());
      return true;
    };
    return a;
  }
};

void expect_plate_walls(const DenseVolume<float>& map, const BitVolume& v) {
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i) ASSERT_EQ(map.at(i, j, k), v.get(i, j, k) ? 4.0f : 0.0f) << i << " " << j << " " << k;
}

TEST(KeptThicknessMap, ASecondAskerWaitsForTheWriteAndReadsItInsteadOfComputingAgain) {
  const BitVolume v = plate();
  MemoryArtifacts store;
  std::promise<void> release;
  store.release_saves = release.get_future().share();
  const server::ArtifactAccess artifacts = store.access();

  // The first asker computes the map and has it while its write is held back.
  std::promise<void> first_has_map;
  std::thread first([&] {
    const server::JobThicknessMap map = server::job_thickness_map(v, artifacts, nullptr);
    expect_plate_walls(*map, v);
    first_has_map.set_value();
  });  // its map goes here: the write is waited for
  first_has_map.get_future().wait();
  store.save_started.get_future().wait();

  // The second waits while the write is under way...
  std::atomic<bool> second_done{false};
  std::shared_ptr<const DenseVolume<float>> second_map;
  std::thread second([&] {
    second_map = server::job_thickness_map(v, artifacts, nullptr).map;
    second_done = true;
  });
  std::this_thread::sleep_for(200ms);  // ample for the plate's computation, had it not waited
  EXPECT_FALSE(second_done);
  // ...and then reads what was kept: one computation, one write.
  release.set_value();
  first.join();
  second.join();
  EXPECT_EQ(store.saves, 1);
  ASSERT_TRUE(second_map);
  expect_plate_walls(*second_map, v);
  EXPECT_EQ(store.kept.size(), 1u);
  EXPECT_EQ(store.kept.begin()->second.size(), v.grid().voxel_count() * sizeof(float));
}

TEST(KeptThicknessMap, AFailedWriteLeavesTheMapUnkeptAndTheRequestAnswered) {
  const BitVolume v = plate();
  MemoryArtifacts store;
  store.fail = true;
  const server::ArtifactAccess artifacts = store.access();
  {
    const server::JobThicknessMap map = server::job_thickness_map(v, artifacts, nullptr);
    expect_plate_walls(*map, v);
  }
  EXPECT_EQ(store.saves, 1);
  EXPECT_TRUE(store.kept.empty());
  // Nothing kept: the next asker computes it again, and keeps it now.
  store.fail = false;
  {
    const server::JobThicknessMap map = server::job_thickness_map(v, artifacts, nullptr);
    expect_plate_walls(*map, v);
  }
  EXPECT_EQ(store.saves, 2);
  EXPECT_EQ(store.kept.size(), 1u);
  // And then it is read, not computed.
  const server::JobThicknessMap again = server::job_thickness_map(v, artifacts, nullptr);
  expect_plate_walls(*again, v);
  EXPECT_EQ(store.saves, 2);
}

}  // namespace
}  // namespace voxd::test
