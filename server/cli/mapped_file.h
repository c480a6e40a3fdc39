#pragma once
// Read-only memory map of an input file: a 50 MB STL is parsed straight from
// the page cache without a copy.
#include <cstdint>
#include <span>
#include <string>

namespace voxd::cli {

class MappedFile {
 public:
  explicit MappedFile(const std::string& path);  // throws Error(io_error)
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  std::span<const std::uint8_t> bytes() const { return {data_, size_}; }

 private:
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
  bool mapped_ = false;
};

}  // namespace voxd::cli
