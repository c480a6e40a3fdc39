#include "server/jobs/stored_blob.h"

#include "server/mapped_file.h"

namespace voxd::server {
namespace {

class MappedBlob final : public StoredBlob {
 public:
  explicit MappedBlob(const std::string& path) : file_(std::make_shared<const MappedFile>(path, MapAccess::sequential)) {}
  std::uint64_t size() const override { return file_->bytes().size(); }
  std::unique_ptr<ByteSource> open() const override { return std::make_unique<Source>(file_); }

 private:
  // A span source that keeps its mapping alive.
  class Source final : public ByteSource {
   public:
    explicit Source(std::shared_ptr<const MappedFile> file) : file_(std::move(file)), span_(file_->bytes()) {}
    std::size_t read(std::uint8_t* out, std::size_t size) override { return span_.read(out, size); }
    std::span<const std::uint8_t> whole() const override { return span_.whole(); }

   private:
    std::shared_ptr<const MappedFile> file_;
    SpanSource span_;
  };
  std::shared_ptr<const MappedFile> file_;
};

}  // namespace

std::shared_ptr<const StoredBlob> mapped_blob(const std::string& path) { return std::make_shared<const MappedBlob>(path); }

}  // namespace voxd::server
