#pragma once
// What colouring a finished job's solid by one slice function after another
// repeats (colour=slice, an editor's updates while a parameter is dragged),
// kept between requests so each update pays only for its colours:
//  - the slicing frame of a job and an axis: its kept mesh read, turned and
//    every vertex projected (tens of milliseconds for a million triangles);
//  - a job's preview rendered from a view: which voxel each pixel shows
//    and its shade (the ray casting through the whole grid).
// Both are the job's own whatever the function, and a finished job's solid
// never changes, so an entry is never stale; job ids are random and never
// reused. The least recently used entries go first: at most kFrames frames
// and kPreviewBytes of previews (a larger preview is not kept).
#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <glm/vec3.hpp>

#include "voxd/analysis/preview.h"
#include "voxd/voxelize/slice_functions.h"

namespace voxd::server {

class SliceEditingCache {
 public:
  static constexpr std::size_t kFrames = 256;
  static constexpr std::uint64_t kPreviewBytes = std::uint64_t{64} << 20;

  std::optional<SliceFrame> frame(const std::string& job, const glm::dvec3& axis);
  void keep_frame(const std::string& job, const glm::dvec3& axis, const SliceFrame& frame);

  std::shared_ptr<const PreviewImage> preview(const std::string& job, View view);
  void keep_preview(const std::string& job, View view, std::shared_ptr<const PreviewImage> preview);

 private:
  struct Frame {
    std::string job;
    glm::dvec3 axis;
    SliceFrame frame;
  };
  struct Preview {
    std::string job;
    View view;
    std::shared_ptr<const PreviewImage> image;
    std::uint64_t bytes;
  };
  std::mutex mutex_;
  std::list<Frame> frames_;      // most recently used first
  std::list<Preview> previews_;  // most recently used first
  std::uint64_t preview_bytes_ = 0;
};

// The service's one cache.
SliceEditingCache& slice_editing_cache();

}  // namespace voxd::server
