// The progress bar a job shows: it only rises, and every stage that runs
// inside another reports within its share, so a watcher never sees the bar
// go back (which a client's progress bar would show as a jump).
#include <mutex>
#include <vector>

#include <gtest/gtest.h>

#include "support/test_meshes.h"
#include "voxd/analysis/analysis.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/error.h"
#include "voxd/progress.h"
#include "voxd/voxelize/slice_functions.h"
#include "voxd/voxelize/voxelize.h"

namespace voxd {
namespace {

using namespace voxd::test;

TEST(JobControl, ShownProgressNeverFallsAndTheLargestStepBackIsKept) {
  JobControl control;
  control.set_progress(0.4);
  control.set_progress(0.3);  // a late report: not shown
  EXPECT_DOUBLE_EQ(control.progress(), 0.4);
  EXPECT_NEAR(control.largest_step_back(), 0.1, 1e-12);
  control.set_progress(0.9);
  control.set_progress(0.85);
  EXPECT_DOUBLE_EQ(control.progress(), 0.9);
  EXPECT_NEAR(control.largest_step_back(), 0.1, 1e-12);  // the larger of the two
}

TEST(JobControl, NestedSpansMapOntoTheirShareAndPutTheSpanBack) {
  JobControl control;
  control.set_span(0.5, 1.0);
  {
    const NestedSpan inner(&control, 0.2, 0.6);  // 0.6 .. 0.8 of the job
    control.set_progress(0.5);
    EXPECT_NEAR(control.progress(), 0.7, 1e-12);
    {
      const NestedSpan innermost(&control, 0.5, 1.0);  // 0.7 .. 0.8
      control.set_progress(1.0);
      EXPECT_NEAR(control.progress(), 0.8, 1e-12);
    }
    EXPECT_NEAR(control.span_begin(), 0.6, 1e-12);
    EXPECT_NEAR(control.span_end(), 0.8, 1e-12);
  }
  EXPECT_DOUBLE_EQ(control.span_begin(), 0.5);
  EXPECT_DOUBLE_EQ(control.span_end(), 1.0);
  EXPECT_DOUBLE_EQ(control.largest_step_back(), 0.0);
  const NestedSpan none(nullptr, 0.0, 0.5);  // no control: nothing to narrow
}

TEST(JobControl, StageIsWhatWasLastSet) {
  JobControl control;
  EXPECT_EQ(control.stage(), "");
  control.set_stage("voxelize");
  control.set_stage("analysis: radiography z");
  EXPECT_EQ(control.stage(), "analysis: radiography z");
}

BitVolume hollow_box_solid() {
  const Mesh mesh = concat({make_box({0, 0, 0}, {20, 16, 12}), flipped(make_box({3, 3, 3}, {17, 13, 9}))});
  GridRequest r;
  r.kind = GridRequest::Kind::voxel_size;
  r.voxel_size = 0.5;
  r.padding = 2;
  return voxelize_parity(mesh, resolve_grid(r, bounds(mesh)), 0, 0, nullptr);
}

// The whole analysis with wall thickness used to report 0.7 and then let the
// thickness restart at 0 (a job's bar went 0.54 -> 0.67 -> 0.60). One
// thread, so every report comes in order and any step back is the code's.
TEST(JobControl, TheAnalysisWithThicknessOnlyRisesWithinItsShare) {
  const BitVolume solid = hollow_box_solid();
  JobControl control;
  control.set_span(0.5, 0.75);
  AnalysisOptions options;
  options.threads = 1;
  options.min_wall_voxels = 2;
  const AnalysisReport report = analyze_volume(solid, options, &control);
  ASSERT_TRUE(report.thickness.has_value());
  EXPECT_DOUBLE_EQ(control.largest_step_back(), 0.0);
  EXPECT_NEAR(control.progress(), 0.75, 1e-12);
  EXPECT_DOUBLE_EQ(control.span_begin(), 0.5);  // the caller's span is put back
  EXPECT_DOUBLE_EQ(control.span_end(), 0.75);
}

TEST(JobControl, TheSliceFunctionsOnlyRiseWithinTheirShare) {
  const Mesh mesh = make_box({0, 0, 0}, {10, 8, 6});
  GridRequest r;
  r.kind = GridRequest::Kind::resolution;
  r.resolution = 24;
  const Grid grid = resolve_grid(r, bounds(mesh));
  JobControl control;
  control.set_span(0.1, 0.9);
  SliceOptions options;
  options.threads = 1;
  const DenseVolume<Rgba8> colours = voxelize_slice(mesh, grid, options, &control);
  EXPECT_EQ(colours.grid().voxel_count(), grid.voxel_count());
  EXPECT_DOUBLE_EQ(control.largest_step_back(), 0.0);
  EXPECT_NEAR(control.progress(), 0.9, 1e-12);
  EXPECT_DOUBLE_EQ(control.span_begin(), 0.1);
  EXPECT_DOUBLE_EQ(control.span_end(), 0.9);
}

// A host embedding the engine watches and stops it through its own
// interrupter, with no job type: it hears the progress rise and stops the
// voxelizer when it says so.
TEST(JobControl, AHostsInterrupterHearsTheProgressAndStopsTheEngine) {
  struct Host final : HostInterrupter {
    std::mutex mutex;
    std::vector<double> heard;
    double stop_at = 2.0;
    bool interrupted() override {
      std::lock_guard lock(mutex);
      return !heard.empty() && heard.back() >= stop_at;
    }
    void progressed(double fraction) override {
      std::lock_guard lock(mutex);
      heard.push_back(fraction);
    }
  };
  const Mesh sphere = make_icosphere({0, 0, 0}, 10.0, 4);
  const Grid grid{glm::dvec3(-10.5), 21.0 / 192, glm::i64vec3(192)};
  const VoxelizeOptions options{VoxelMode::solid, InsideTest::parity, 2};

  Host watcher;
  JobControl control(&watcher);
  const BitVolume solid = voxelize(sphere, grid, options, &control);
  EXPECT_GT(solid.count(), 0u);
  ASSERT_GT(watcher.heard.size(), 2u);
  for (std::size_t i = 1; i < watcher.heard.size(); ++i) EXPECT_GT(watcher.heard[i], watcher.heard[i - 1]) << i;
  EXPECT_DOUBLE_EQ(watcher.heard.back(), control.progress());
  EXPECT_NEAR(control.progress(), 1.0, 1e-9);

  Host stopper;
  stopper.stop_at = 0.2;
  JobControl stopped(&stopper);
  try {
    (void)voxelize(sphere, grid, options, &stopped);
    ADD_FAILURE() << "the host asked to stop, and the voxelizer ran to the end";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::cancelled);
  }
  EXPECT_LT(stopped.progress(), 1.0);
}

}  // namespace
}  // namespace voxd
