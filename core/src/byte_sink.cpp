#include "voxd/byte_sink.h"

#include <cerrno>
#include <cstring>

#include "voxd/error.h"

namespace voxd {

FileSink::FileSink(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "wb")) {
  if (!file_) throw Error(ErrorCode::io_error, "cannot open '" + path + "' for writing: " + std::strerror(errno));
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
}

FileSink::~FileSink() {
  if (file_) std::fclose(file_);
}

void FileSink::write(std::span<const std::uint8_t> bytes) {
  if (bytes.empty()) return;
  if (!file_) throw Error(ErrorCode::io_error, "write to closed file '" + path_ + "'");
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size())
    throw Error(ErrorCode::io_error, "cannot write '" + path_ + "': " + std::strerror(errno));
}

void FileSink::close() {
  if (!file_) return;
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (rc != 0) throw Error(ErrorCode::io_error, "cannot finish writing '" + path_ + "': " + std::strerror(errno));
}

}  // namespace voxd
