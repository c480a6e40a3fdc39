#pragma once
// Where jobs are kept: their records (the job snapshot) and result blobs (the
// volume, the layers of values, derived artifacts). The job engine only talks
// to this interface; the embedded implementation is the local data directory
// (server/jobs/local_job_store.h). A shared backend (replicas on one Redis)
// implements the same calls.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <span>
#include <string_view>
#include <vector>

#include "server/jobs/job.h"
#include "server/jobs/stored_blob.h"
#include "voxd/bit_volume.h"
#include "voxd/byte_sink.h"
#include "voxd/encode/volume_format.h"
#include "voxd/voxelize/streamed.h"

namespace voxd::server {

// The store has no room (ENOSPC, EDQUOT, EFBIG): HTTP 507. The write that
// failed has left nothing behind.
class StorageFull : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The shared backend (Redis) cannot be reached: HTTP 503 backend-unavailable,
// /readyz not ready. Nothing was changed by the call that threw it.
class BackendUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Slabs replayed from a stored volume (trusted: written by the service) are
// at least one layer of a grid of up to kMaxGridDim^2 voxels a layer.
inline constexpr ReadLimits kStoredSlabLimits{std::uint64_t{4} << 30};

// A stored volume read whole is trusted to be as large as the job limits let
// it be (8 Gi voxels), not the untrusted-input default of 1 GiB.
inline constexpr ReadLimits kStoredVolumeLimits{std::uint64_t{1} << 36};
// A stored layer's RLE of values of `type` ("u8", "f32", "rgba8"), decoded.
ValueVolume read_stored_layer(std::string_view type, std::span<const std::uint8_t> rle);

// A stored result is replayed (re-encoded, analysed) in slabs of about
// 16 MiB: small beside the images, large enough that a slab is cheap to
// hand on. Z layers per slab of bits, and of values (up to 4 bytes each).
inline constexpr std::uint64_t kReplaySlabBytes = std::uint64_t{16} << 20;
inline std::int64_t replay_bit_slab_layers(const Grid& grid) { return streamed_slab_layers(grid, kReplaySlabBytes); }
inline std::int64_t replay_value_slab_layers(const Grid& grid) {
  const std::uint64_t layer = static_cast<std::uint64_t>(grid.dims.x) * static_cast<std::uint64_t>(grid.dims.y) * 4;
  return static_cast<std::int64_t>(kReplaySlabBytes / std::max<std::uint64_t>(layer, 1));
}

class JobStore {
 public:
  virtual ~JobStore() = default;

  // Every readable record; unreadable ones are logged and skipped.
  virtual std::vector<JobSnapshot> load_all() const = 0;
  // Writes (replaces) a job's record. Throws StorageFull.
  virtual void save(const JobSnapshot& job) const = 0;
  virtual std::optional<std::string> load_artifact(const std::string& id, const std::string& key) const = 0;
  // An artifact of exactly out.size() bytes read into `out` (a kept
  // thickness map into its volume: no second copy of hundreds of
  // megabytes). False, `out` unspecified, when there is none of that size.
  virtual bool load_artifact_into(const std::string& id, const std::string& key, std::span<char> out) const;
  virtual void save_artifact(const std::string& id, const std::string& key, std::string_view bytes) const = 0;
  virtual void save_volume(const std::string& id, const BitVolume& volume) const = 0;
  virtual std::shared_ptr<const BitVolume> load_volume(const std::string& id) const = 0;
  // A volume made slab by slab: `write` writes its RLE (the bytes
  // save_volume would), never holding it whole; kept as atomically. Throws
  // StorageFull, or what `write` throws (then nothing is kept).
  virtual void write_volume(const std::string& id, const std::function<void(ByteSink&)>& write) const = 0;
  // The stored RLE of the job's volume, to be read front to back
  // (voxd/encode/rle_slabs.h); nullptr when there is none.
  virtual std::shared_ptr<const StoredBlob> volume_rle(const std::string& id) const = 0;
  // A value job's volume of values by name ("values", the result, or a layer
  // its mode keeps beside it, api::JobMode::stored_layers()).
  virtual void save_layer(const std::string& id, const std::string& name, const ValueVolume& values) const = 0;
  virtual std::shared_ptr<const ValueVolume> load_layer(const std::string& id, const std::string& name) const = 0;
  // A volume of values made slab by slab (a streamed job's "values", of
  // `type`'s type): `write` writes its RLE (the bytes save_layer would), kept
  // as atomically; and that stored RLE, to be read front to back (nullptr
  // when there is none).
  virtual void write_layer(const std::string& id, const std::string& name, const ValueVolume& type,
                           const std::function<void(ByteSink&)>& write) const = 0;
  virtual std::shared_ptr<const StoredBlob> layer_rle(const std::string& id, const std::string& name) const = 0;
  // Shares a finished result (volume and layers) with a job created from an
  // identical submission, so that deleting either leaves the other's intact.
  // Throws when the original's result is gone.
  virtual void share_volume(const std::string& from_id, const std::string& to_id) const = 0;
  // Bytes a job's blobs take (its result, layers and artifacts).
  virtual std::uint64_t stored_bytes(const std::string& id) const = 0;
  // Removes a job's record and blobs.
  virtual void remove(const std::string& id) const = 0;
  // Bytes the store has free for this process.
  virtual std::uint64_t free_bytes() const = 0;
  // Why it is not ready when free_bytes() is under --min-free-disk, in words
  // that name what is full.
  virtual std::string full_reason() const = 0;
};

}  // namespace voxd::server
