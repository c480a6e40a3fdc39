// ZIP writing (APPNOTE 6.3.x, sections 4.3.7 local file header, 4.3.12
// central directory header, 4.3.16 end of central directory record). All
// fields are little-endian. The values 0xFFFF and 0xFFFFFFFF announce ZIP64
// records to a reader, so counts stay at most 0xFFFF and sizes and offsets
// below 0xFFFFFFFF.
#include "voxd/encode/zip_archive.h"

#include <zlib.h>

#include <stdexcept>
#include <string>

#include "voxd/error.h"

namespace voxd {
namespace {

constexpr std::uint32_t kLocalHeaderSignature = 0x04034b50;
constexpr std::uint32_t kCentralHeaderSignature = 0x02014b50;
constexpr std::uint32_t kEndSignature = 0x06054b50;
constexpr std::size_t kLocalHeaderBytes = 30;
constexpr std::size_t kMaxEntries = 0xFFFF;
constexpr std::uint64_t kMax32 = 0xFFFFFFFEu;  // 0xFFFFFFFF itself means "see ZIP64"
constexpr std::uint16_t kMethodStored = 0;
constexpr std::uint16_t kMethodDeflated = 8;
// 2.0 is the version that introduced deflate; stored needs 1.0.
constexpr std::uint16_t kVersionStored = 10;
constexpr std::uint16_t kVersionDeflated = 20;
// High byte 3: Unix, so readers take the permissions from the external
// attributes; low byte: spec version 2.0.
constexpr std::uint16_t kVersionMadeBy = (3 << 8) | 20;
constexpr std::uint32_t kExternalAttributes = 0100644u << 16;  // regular file, rw-r--r--
// DOS date 1980-01-01 (day 1, month 1, year 1980 + 0), time 00:00:00.
constexpr std::uint16_t kDosTime = 0;
constexpr std::uint16_t kDosDate = (0 << 9) | (1 << 5) | 1;
constexpr std::uint16_t kFlagUtf8 = 1 << 11;

void put16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v));
  out.push_back(static_cast<std::uint8_t>(v >> 8));
}

void put32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int shift = 0; shift < 32; shift += 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

void put_name(std::vector<std::uint8_t>& out, const std::string& name) { out.insert(out.end(), name.begin(), name.end()); }

void check_name(std::string_view name) {
  if (name.empty() || name.size() > 0xFFFF)
    throw Error(ErrorCode::invalid_argument,
                "ZIP entry name must be 1 to 65535 bytes, got " + std::to_string(name.size()));
  // A leading '/' or a backslash makes extractors write outside the target
  // folder or misread the path; NUL ends the name for C readers.
  if (name.front() == '/' || name.find('\\') != std::string_view::npos || name.find('\0') != std::string_view::npos)
    throw Error(ErrorCode::invalid_argument,
                "ZIP entry name \"" + std::string(name) + "\" must not start with '/' or contain '\\' or NUL");
}

// Raw deflate (no zlib or gzip wrapper: ZIP stores the bare stream).
std::vector<std::uint8_t> deflate_raw(std::span<const std::uint8_t> data) {
  z_stream z{};
  if (deflateInit2(&z, Z_DEFAULT_COMPRESSION, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw std::runtime_error("zlib deflateInit2 failed");
  std::vector<std::uint8_t> out(deflateBound(&z, static_cast<uLong>(data.size())));
  // Callers keep sizes below 4 GiB, so they fit zlib's 32-bit counters.
  z.next_in = const_cast<Bytef*>(data.data());
  z.avail_in = static_cast<uInt>(data.size());
  z.next_out = out.data();
  z.avail_out = static_cast<uInt>(out.size());
  const int rc = deflate(&z, Z_FINISH);
  const std::size_t produced = out.size() - z.avail_out;
  deflateEnd(&z);
  // deflateBound guarantees room for one Z_FINISH call.
  if (rc != Z_STREAM_END) throw std::runtime_error("zlib deflate failed");
  out.resize(produced);
  return out;
}

std::uint32_t crc_of(std::span<const std::uint8_t> data) {
  return static_cast<std::uint32_t>(crc32_z(0, data.data(), data.size()));
}

}  // namespace

ZipWriter::ZipWriter(ByteSink& sink) : sink_(sink) {}

void ZipWriter::emit(std::span<const std::uint8_t> bytes) {
  sink_.write(bytes);
  offset_ += bytes.size();
}

void ZipWriter::add(std::string_view name, std::span<const std::uint8_t> data, bool deflate) {
  if (finished_) throw std::logic_error("ZIP entry added after finish()");
  check_name(name);
  if (entries_.size() >= kMaxEntries)
    throw Error(ErrorCode::limit_exceeded,
                "a ZIP archive without ZIP64 holds at most " + std::to_string(kMaxEntries) + " entries");
  if (data.size() > kMax32)
    throw Error(ErrorCode::limit_exceeded, "ZIP entry \"" + std::string(name) + "\" of " + std::to_string(data.size()) +
                                               " bytes exceeds the 4 GiB a ZIP archive without ZIP64 can hold");

  std::vector<std::uint8_t> compressed;
  if (deflate) compressed = deflate_raw(data);
  const std::span<const std::uint8_t> payload = deflate ? std::span<const std::uint8_t>(compressed) : data;
  // The end of this entry is where the next one, or the central directory,
  // starts: it must fit a 32-bit offset too.
  const std::uint64_t end = offset_ + kLocalHeaderBytes + name.size() + payload.size();
  if (end > kMax32)
    throw Error(ErrorCode::limit_exceeded, "ZIP entry \"" + std::string(name) +
                                               "\" would end past 4 GiB, more than a ZIP archive without ZIP64 can hold");

  Entry e;
  e.name = std::string(name);
  e.crc = crc_of(data);
  e.compressed_size = static_cast<std::uint32_t>(payload.size());
  e.size = static_cast<std::uint32_t>(data.size());
  e.offset = static_cast<std::uint32_t>(offset_);
  e.method = deflate ? kMethodDeflated : kMethodStored;
  for (const char c : name)
    if (static_cast<unsigned char>(c) >= 0x80) e.flags = kFlagUtf8;

  std::vector<std::uint8_t> header;
  header.reserve(kLocalHeaderBytes + e.name.size());
  put32(header, kLocalHeaderSignature);
  put16(header, deflate ? kVersionDeflated : kVersionStored);
  put_entry_fields(header, e);
  put16(header, 0);  // no extra field
  put_name(header, e.name);
  emit(header);
  if (!payload.empty()) emit(payload);
  entries_.push_back(std::move(e));
}

// The fields a local header and its central directory record share, in the
// same order: flags, method, time, date, CRC-32, sizes, name length.
void ZipWriter::put_entry_fields(std::vector<std::uint8_t>& out, const Entry& e) {
  put16(out, e.flags);
  put16(out, e.method);
  put16(out, kDosTime);
  put16(out, kDosDate);
  put32(out, e.crc);
  put32(out, e.compressed_size);
  put32(out, e.size);
  put16(out, static_cast<std::uint16_t>(e.name.size()));
}

void ZipWriter::finish() {
  if (finished_) return;
  std::vector<std::uint8_t> directory;
  for (const Entry& e : entries_) {
    put32(directory, kCentralHeaderSignature);
    put16(directory, kVersionMadeBy);
    put16(directory, e.method == kMethodDeflated ? kVersionDeflated : kVersionStored);
    put_entry_fields(directory, e);
    put16(directory, 0);  // extra field length
    put16(directory, 0);  // comment length
    put16(directory, 0);  // disk number start
    put16(directory, 0);  // internal attributes: binary
    put32(directory, kExternalAttributes);
    put32(directory, e.offset);
    put_name(directory, e.name);
  }
  if (directory.size() > kMax32 || offset_ + directory.size() > kMax32)
    throw Error(ErrorCode::limit_exceeded,
                "the ZIP central directory would end past 4 GiB, more than a ZIP archive without ZIP64 can hold");
  const auto directory_offset = static_cast<std::uint32_t>(offset_);
  const auto directory_size = static_cast<std::uint32_t>(directory.size());
  const auto count = static_cast<std::uint16_t>(entries_.size());
  put32(directory, kEndSignature);
  put16(directory, 0);  // this disk
  put16(directory, 0);  // disk with the central directory
  put16(directory, count);
  put16(directory, count);
  put32(directory, directory_size);
  put32(directory, directory_offset);
  put16(directory, 0);  // comment length
  emit(directory);
  finished_ = true;
}

}  // namespace voxd
