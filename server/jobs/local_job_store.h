#pragma once
// The embedded job store: one directory per job under DATA_DIR/jobs/ID with
// record.json (the job snapshot) and, once succeeded, volume.rle and, for a
// value job, its layers of values as NAME.TYPE.rle (values.f32.rle, and e.g.
// similarity.u8.rle for a mode that keeps more, api::JobMode::stored_layers),
// and artifacts/KEY for derived results. Every file is written to a
// temporary name, flushed to disk and renamed, so a crash or a kill never
// leaves a half-written record or result behind. Shared results are hard
// links.
#include <filesystem>

#include "server/jobs/job_store.h"

namespace voxd::server {

class LocalJobStore final : public JobStore {
 public:
  explicit LocalJobStore(std::filesystem::path data_dir);  // creates DATA_DIR/jobs

  std::vector<JobSnapshot> load_all() const override;
  void save(const JobSnapshot& job) const override;
  std::optional<std::string> load_artifact(const std::string& id, const std::string& key) const override;
  bool load_artifact_into(const std::string& id, const std::string& key, std::span<char> out) const override;
  void save_artifact(const std::string& id, const std::string& key, std::string_view bytes) const override;
  void save_volume(const std::string& id, const BitVolume& volume) const override;
  std::shared_ptr<const BitVolume> load_volume(const std::string& id) const override;
  void write_volume(const std::string& id, const std::function<void(ByteSink&)>& write) const override;
  std::shared_ptr<const StoredBlob> volume_rle(const std::string& id) const override;
  void save_layer(const std::string& id, const std::string& name, const ValueVolume& values) const override;
  std::shared_ptr<const ValueVolume> load_layer(const std::string& id, const std::string& name) const override;
  void write_layer(const std::string& id, const std::string& name, const ValueVolume& type,
                   const std::function<void(ByteSink&)>& write) const override;
  std::shared_ptr<const StoredBlob> layer_rle(const std::string& id, const std::string& name) const override;
  void share_volume(const std::string& from_id, const std::string& to_id) const override;
  std::uint64_t stored_bytes(const std::string& id) const override;
  void remove(const std::string& id) const override;
  std::uint64_t free_bytes() const override;
  std::string full_reason() const override { return "the data directory's disk is full"; }

 private:
  std::filesystem::path job_dir(const std::string& id) const { return jobs_ / id; }
  std::filesystem::path jobs_;
};

}  // namespace voxd::server
