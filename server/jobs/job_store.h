#pragma once
// The embedded job store: one directory per job under DATA_DIR/jobs/ID with
// record.json (the job snapshot) and, once succeeded, volume.rle. Every file is
// written to a temporary name, flushed to disk and renamed, so a crash or a
// kill never leaves a half-written record or result behind.
#include <filesystem>
#include <optional>
#include <memory>
#include <string>
#include <vector>

#include "server/jobs/job_manager.h"
#include "voxd/bit_volume.h"

namespace voxd::server {

class JobStore {
 public:
  explicit JobStore(std::filesystem::path data_dir);  // creates DATA_DIR/jobs

  // Every readable record; unreadable ones are logged and skipped.
  std::vector<JobSnapshot> load_all() const;
  std::optional<std::string> load_artifact(const std::string& id, const std::string& key) const;
  void save_artifact(const std::string& id, const std::string& key, const std::string& bytes) const;
  void save(const JobSnapshot& job) const;
  void save_volume(const std::string& id, const BitVolume& volume) const;
  // Shares a finished result with a job created from an identical submission:
  // a hard link, so deleting either job leaves the other's file intact.
  void share_volume(const std::string& from_id, const std::string& to_id) const;
  std::shared_ptr<const BitVolume> load_volume(const std::string& id) const;
  void remove(const std::string& id) const;

 private:
  std::filesystem::path job_dir(const std::string& id) const { return jobs_ / id; }
  std::filesystem::path jobs_;
};

}  // namespace voxd::server
