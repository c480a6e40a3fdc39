#include "server/jobs/analyses/slice_editing_cache.h"

namespace voxd::server {
namespace {

std::uint64_t bytes_of(const PreviewImage& p) {
  return p.voxel.size() * sizeof(std::int64_t) + p.shade.size() * sizeof(float) + p.normal.size() * sizeof(glm::vec3);
}

bool same(View a, View b) { return a.axis == b.axis && a.from_positive == b.from_positive; }

}  // namespace

std::optional<SliceFrame> SliceEditingCache::frame(const std::string& job, const glm::dvec3& axis) {
  const std::lock_guard lock(mutex_);
  for (auto it = frames_.begin(); it != frames_.end(); ++it)
    if (it->job == job && it->axis == axis) {
      frames_.splice(frames_.begin(), frames_, it);
      return frames_.front().frame;
    }
  return std::nullopt;
}

void SliceEditingCache::keep_frame(const std::string& job, const glm::dvec3& axis, const SliceFrame& frame) {
  const std::lock_guard lock(mutex_);
  for (const Frame& f : frames_)
    if (f.job == job && f.axis == axis) return;
  frames_.push_front({job, axis, frame});
  if (frames_.size() > kFrames) frames_.pop_back();
}

std::shared_ptr<const PreviewImage> SliceEditingCache::preview(const std::string& job, View view) {
  const std::lock_guard lock(mutex_);
  for (auto it = previews_.begin(); it != previews_.end(); ++it)
    if (it->job == job && same(it->view, view)) {
      previews_.splice(previews_.begin(), previews_, it);
      return previews_.front().image;
    }
  return nullptr;
}

void SliceEditingCache::keep_preview(const std::string& job, View view, std::shared_ptr<const PreviewImage> preview) {
  const std::uint64_t bytes = bytes_of(*preview);
  if (bytes > kPreviewBytes) return;
  const std::lock_guard lock(mutex_);
  for (const Preview& p : previews_)
    if (p.job == job && same(p.view, view)) return;
  previews_.push_front({job, view, std::move(preview), bytes});
  preview_bytes_ += bytes;
  while (preview_bytes_ > kPreviewBytes) {
    preview_bytes_ -= previews_.back().bytes;
    previews_.pop_back();
  }
}

SliceEditingCache& slice_editing_cache() {
  static SliceEditingCache cache;
  return cache;
}

}  // namespace voxd::server
