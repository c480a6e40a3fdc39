#pragma once
// A stored result's bytes (a streamed job's RLE), read front to back as
// often as asked: a file of the local store where it lies, or the shared
// store's chunks fetched as they are read. Either way nothing holds the
// whole result in memory or copies it to disk to serve it.
#include <cstdint>
#include <memory>
#include <string>

#include "voxd/byte_source.h"

namespace voxd::server {

class StoredBlob {
 public:
  virtual ~StoredBlob() = default;
  virtual std::uint64_t size() const = 0;
  // A fresh reader from the first byte. Its reads throw voxd::Error
  // (io_error) when the store loses the bytes meanwhile (deleted, expired).
  virtual std::unique_ptr<ByteSource> open() const = 0;
};

// A file, mapped to be read front to back (throws Error(io_error)).
std::shared_ptr<const StoredBlob> mapped_blob(const std::string& path);

}  // namespace voxd::server
