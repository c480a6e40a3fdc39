#pragma once
// Read-only memory map of a file: a 50 MB STL is parsed straight from the
// page cache without a copy, and a stored result larger than memory is read
// slab by slab with the kernel reading ahead and dropping what was read.
#include <cstdint>
#include <span>
#include <string>

namespace voxd {

// whole: read all of it now (an upload, parsed at once); sequential: read
// on demand, front to back (a stored result replayed slab by slab).
enum class MapAccess { whole, sequential };

class MappedFile {
 public:
  explicit MappedFile(const std::string& path, MapAccess access = MapAccess::whole);  // throws Error(io_error)
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  std::span<const std::uint8_t> bytes() const { return {data_, size_}; }

 private:
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
  bool mapped_ = false;
};

}  // namespace voxd
