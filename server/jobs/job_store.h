#pragma once
// The embedded job store: one directory per job under DATA_DIR/jobs/ID with
// record.json (the job snapshot) and, once succeeded, volume.rle and, for a
// value job, its layers of values as NAME.TYPE.rle (values.f32.rle, and e.g.
// similarity.u8.rle for a mode that keeps more, api::JobMode::stored_layers).
// Every file is
// written to a temporary name, flushed to disk and renamed, so a crash or a
// kill never leaves a half-written record or result behind.
#include <filesystem>
#include <optional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "server/jobs/job_manager.h"
#include "voxd/bit_volume.h"
#include "voxd/encode/volume_format.h"

namespace voxd::server {

// The data directory's disk has no room (ENOSPC, EDQUOT, EFBIG): HTTP 507.
// The write that failed has left nothing behind.
class StorageFull : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class JobStore {
 public:
  explicit JobStore(std::filesystem::path data_dir);  // creates DATA_DIR/jobs

  // Every readable record; unreadable ones are logged and skipped.
  std::vector<JobSnapshot> load_all() const;
  std::optional<std::string> load_artifact(const std::string& id, const std::string& key) const;
  void save_artifact(const std::string& id, const std::string& key, const std::string& bytes) const;
  void save(const JobSnapshot& job) const;
  void save_volume(const std::string& id, const BitVolume& volume) const;
  // A value job's volume of values by name ("values", the result, or a
  // layer its mode keeps beside it), as RLE beside the volume.
  void save_layer(const std::string& id, const std::string& name, const ValueVolume& values) const;
  std::shared_ptr<const ValueVolume> load_layer(const std::string& id, const std::string& name) const;
  // Shares a finished result (volume and values) with a job created from an
  // identical submission: hard links, so deleting either job leaves the
  // other's files intact.
  void share_volume(const std::string& from_id, const std::string& to_id) const;
  std::shared_ptr<const BitVolume> load_volume(const std::string& id) const;
  void remove(const std::string& id) const;
  // Bytes the data directory's file system has free for this process.
  std::uint64_t free_bytes() const;

 private:
  std::filesystem::path job_dir(const std::string& id) const { return jobs_ / id; }
  std::filesystem::path jobs_;
};

}  // namespace voxd::server
