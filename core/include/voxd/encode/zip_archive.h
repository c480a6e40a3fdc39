#pragma once
// A minimal ZIP writer (PKWARE APPNOTE 6.3.x) for bundling encoder outputs,
// e.g. a PNG per layer (voxd/encode/png_stack.h). Each add() writes its entry at
// once (local file header, then the data), so the sink sees the archive
// grow entry by entry and the writer keeps only the small central directory
// records; finish() writes the central directory and the end record.
//
// Reproducible output: every entry carries the DOS time 1980-01-01 00:00
// (the earliest the format can say) and Unix permissions 0644, so equal
// inputs give equal archives byte for byte.
//
// No ZIP64: an archive is refused (Error(limit_exceeded)) past 65535
// entries, or when an entry's size, an offset, or the central directory
// would not fit the classic 32-bit fields. Entries are stored or deflated
// (raw deflate, zlib's default level); the whole entry is in memory anyway,
// so sizes and CRC-32 go in the local header and no data descriptor is
// needed.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxd/byte_sink.h"

namespace voxd {

class ZipWriter {
 public:
  explicit ZipWriter(ByteSink& sink);
  ZipWriter(const ZipWriter&) = delete;
  ZipWriter& operator=(const ZipWriter&) = delete;

  // Writes one entry. `name` is the path inside the archive ("a/b.png"):
  // 1 to 65535 bytes, no NUL, no backslash, not starting with '/'
  // (Error(invalid_argument) otherwise); non-ASCII names are flagged as
  // UTF-8. `deflate` compresses the data; leave it off for data that is
  // compressed already (PNG), where deflate only costs time. Throws
  // Error(limit_exceeded) past the limits above, and std::logic_error after
  // finish().
  void add(std::string_view name, std::span<const std::uint8_t> data, bool deflate);
  // Writes the central directory and the end record. Without it the archive
  // is incomplete (readers find entries through the central directory).
  // Calling it again does nothing.
  void finish();

 private:
  struct Entry {
    std::string name;
    std::uint32_t crc = 0;
    std::uint32_t compressed_size = 0;
    std::uint32_t size = 0;
    std::uint32_t offset = 0;
    std::uint16_t method = 0;
    std::uint16_t flags = 0;
  };

  void emit(std::span<const std::uint8_t> bytes);
  static void put_entry_fields(std::vector<std::uint8_t>& out, const Entry& e);

  ByteSink& sink_;
  std::vector<Entry> entries_;
  std::uint64_t offset_ = 0;  // bytes written so far
  bool finished_ = false;
};

}  // namespace voxd
