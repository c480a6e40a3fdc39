#include "server/jobs/local_job_store.h"

#include "server/jobs/kept_mesh.h"


#include <fcntl.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

#include <spdlog/spdlog.h>

#include "server/jobs/job_record.h"
#include "voxd/byte_sink.h"
#include "voxd/error.h"
#include "voxd/encode/volume_format.h"

namespace voxd::server {
namespace {

namespace fs = std::filesystem;

void fsync_path(const fs::path& p, int flags) {
  const int fd = ::open(p.c_str(), flags | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

// Writes through `write` into a temporary file, then fsyncs and renames it.
void make_dirs(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec == std::errc::no_space_on_device) throw StorageFull("the service's disk is full (" + ec.message() + ")");
  if (ec) throw fs::filesystem_error("cannot create the job directory", dir, ec);
}

// A failed write removes its temporary file (a full disk stays full
// otherwise) and reports a full disk as StorageFull.
template <typename WriteFn>
void write_atomically(const fs::path& target, WriteFn&& write) {
  const fs::path tmp = target.string() + ".tmp";
  try {
    {
      FileSink sink(tmp.string());
      write(sink);
      sink.close();
    }
    fsync_path(tmp, O_RDONLY);
    fs::rename(tmp, target);
  } catch (const std::exception& e) {
    const int err = errno;
    std::error_code ignored;
    fs::remove(tmp, ignored);
    if (err == ENOSPC || err == EDQUOT || err == EFBIG)
      throw StorageFull("the service's disk is full (" + std::string(std::strerror(err)) + ")");
    throw;
  }
  fsync_path(target.parent_path(), O_RDONLY | O_DIRECTORY);
}

}  // namespace

std::uint64_t LocalJobStore::free_bytes() const {
  struct statvfs s {};
  if (::statvfs(jobs_.c_str(), &s) != 0) return UINT64_MAX;  // unknown: do not refuse on it
  return static_cast<std::uint64_t>(s.f_bavail) * s.f_frsize;
}

LocalJobStore::LocalJobStore(fs::path data_dir) : jobs_(std::move(data_dir) / "jobs") {
  std::error_code ec;
  fs::create_directories(jobs_, ec);
  if (ec) throw Error(ErrorCode::io_error, "cannot create data directory '" + jobs_.string() + "': " + ec.message());
}

std::vector<JobSnapshot> LocalJobStore::load_all() const {
  std::vector<JobSnapshot> jobs;
  for (const auto& entry : fs::directory_iterator(jobs_)) {
    if (!entry.is_directory()) continue;
    const fs::path record = entry.path() / "record.json";
    try {
      std::ifstream in(record);
      if (!in) throw std::runtime_error("missing record.json");
      JobSnapshot job = job_from_json(nlohmann::json::parse(in));
      if (job.id != entry.path().filename().string()) throw std::runtime_error("id does not match its directory");
      jobs.push_back(std::move(job));
    } catch (const std::exception& e) {
      spdlog::warn("job store: skipping unreadable job record {}: {}", record.string(), e.what());
    }
  }
  return jobs;
}

void LocalJobStore::save(const JobSnapshot& job) const {
  make_dirs(job_dir(job.id));
  const std::string text = stored_record(job).dump();
  write_atomically(job_dir(job.id) / "record.json", [&](ByteSink& sink) { sink.write(text.data(), text.size()); });
}

// Read straight into a string of the file's size: a kept thickness map or
// volume is hundreds of megabytes, and a string stream grew by doubling and
// copied it once more at the end (over 1 GB moved for a 400 MB map).
std::optional<std::string> LocalJobStore::load_artifact(const std::string& id, const std::string& key) const {
  std::ifstream in(job_dir(id) / "artifacts" / key, std::ios::binary | std::ios::ate);
  if (!in) return std::nullopt;
  const std::streamoff size = in.tellg();
  if (size < 0) return std::nullopt;
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.seekg(0);
  if (!in.read(bytes.data(), size)) return std::nullopt;
  return bytes;
}

bool LocalJobStore::load_artifact_into(const std::string& id, const std::string& key, std::span<char> out) const {
  std::ifstream in(job_dir(id) / "artifacts" / key, std::ios::binary | std::ios::ate);
  if (!in || in.tellg() != static_cast<std::streamoff>(out.size())) return false;
  in.seekg(0);
  return static_cast<bool>(in.read(out.data(), static_cast<std::streamsize>(out.size())));
}

void LocalJobStore::save_artifact(const std::string& id, const std::string& key, std::string_view bytes) const {
  make_dirs(job_dir(id) / "artifacts");
  write_atomically(job_dir(id) / "artifacts" / key, [&](ByteSink& sink) { sink.write(bytes.data(), bytes.size()); });
}

void LocalJobStore::save_volume(const std::string& id, const BitVolume& volume) const {
  write_volume(id, [&](ByteSink& sink) { write_rle(volume, sink); });
}

void LocalJobStore::write_volume(const std::string& id, const std::function<void(ByteSink&)>& write) const {
  make_dirs(job_dir(id));
  write_atomically(job_dir(id) / "volume.rle", write);
}

std::shared_ptr<const StoredBlob> LocalJobStore::volume_rle(const std::string& id) const {
  const fs::path path = job_dir(id) / "volume.rle";
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return nullptr;
  return mapped_blob(path.string());
}

void LocalJobStore::save_layer(const std::string& id, const std::string& name, const ValueVolume& values) const {
  write_layer(id, name, values, [&](ByteSink& sink) { encode_volume(values, VolumeFormat::rle, sink); });
}

void LocalJobStore::write_layer(const std::string& id, const std::string& name, const ValueVolume& type,
                                const std::function<void(ByteSink&)>& write) const {
  make_dirs(job_dir(id));
  write_atomically(job_dir(id) / (name + "." + value_type_name(type) + ".rle"), write);
}

std::shared_ptr<const StoredBlob> LocalJobStore::layer_rle(const std::string& id, const std::string& name) const {
  for (const char* type : {"u8", "f32", "rgba8"}) {
    const fs::path path = job_dir(id) / (name + "." + type + ".rle");
    std::error_code ec;
    if (fs::is_regular_file(path, ec)) return mapped_blob(path.string());
  }
  return nullptr;
}

void LocalJobStore::share_volume(const std::string& from_id, const std::string& to_id) const {
  make_dirs(job_dir(to_id));
  // The volume must be there (else the original is gone: throw); then every
  // layer of values the original has.
  std::vector<fs::path> files{job_dir(from_id) / "volume.rle"};
  for (const auto& entry : fs::directory_iterator(job_dir(from_id)))
    if (entry.path().extension() == ".rle" && entry.path().filename() != "volume.rle") files.push_back(entry.path());
  // And the mesh it keeps beside them (kept_mesh.h), where it has one.
  const fs::path mesh = fs::path("artifacts") / kKeptMeshKey;
  if (fs::exists(job_dir(from_id) / mesh)) {
    make_dirs(job_dir(to_id) / "artifacts");
    files.push_back(job_dir(from_id) / mesh);
  }
  for (const fs::path& from : files) {
    const fs::path to = job_dir(to_id) / fs::relative(from, job_dir(from_id));
    std::error_code ec;
    fs::create_hard_link(from, to, ec);
    if (ec) fs::copy_file(from, to, fs::copy_options::overwrite_existing);
  }
}

namespace {

std::optional<std::vector<std::uint8_t>> read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  return std::vector<std::uint8_t>{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

std::shared_ptr<const BitVolume> LocalJobStore::load_volume(const std::string& id) const {
  const auto bytes = read_file(job_dir(id) / "volume.rle");
  if (!bytes) return nullptr;
  return std::make_shared<const BitVolume>(read_rle_bits(*bytes, kStoredVolumeLimits));
}

std::shared_ptr<const ValueVolume> LocalJobStore::load_layer(const std::string& id, const std::string& name) const {
  for (const char* type : {"u8", "f32", "rgba8"})
    if (const auto bytes = read_file(job_dir(id) / (name + "." + type + ".rle")))
      return std::make_shared<const ValueVolume>(read_stored_layer(type, *bytes));
  return nullptr;
}

std::uint64_t LocalJobStore::stored_bytes(const std::string& id) const {
  std::uint64_t n = 0;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(job_dir(id), ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec)) n += it->file_size(ec);
  return n;
}

void LocalJobStore::remove(const std::string& id) const {
  std::error_code ec;
  fs::remove_all(job_dir(id), ec);
  if (ec) spdlog::warn("job store: cannot remove {}: {}", job_dir(id).string(), ec.message());
}

}  // namespace voxd::server
