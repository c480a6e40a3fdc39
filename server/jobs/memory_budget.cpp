#include "server/jobs/memory_budget.h"

#include <unistd.h>

#include <fstream>

#include "voxd/error.h"
#include "voxd/encode/number_text.h"

namespace voxd::server {
namespace {

std::string mib(std::uint64_t bytes) { return std::to_string((bytes + (1 << 20) - 1) >> 20) + " MiB"; }

}  // namespace

MemoryBudget::Reservation MemoryBudget::reserve(std::uint64_t bytes, const std::string& what) {
  if (bytes > total_)
    throw Error(ErrorCode::limit_exceeded, what + " needs about " + mib(bytes) + " of memory, more than the " + mib(total_) +
                                               " this service works in (--memory-budget); use a lower resolution "
                                               "or a larger voxel_size");
  std::lock_guard lock(mutex_);
  if (used_ + bytes > total_)
    throw MemoryBusy(what + " needs about " + mib(bytes) + " of memory and only " + mib(total_ - used_) + " of the " +
                     mib(total_) + " budget is free now; retry later");
  used_ += bytes;
  return Reservation(this, bytes);
}

std::uint64_t available_memory() {
  const auto pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  std::uint64_t memory = pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page)
                                               : std::uint64_t{4} << 30;
  for (const char* path : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream in(path);
    std::string text;
    if (in >> text && !text.empty() && text != "max") {
      if (const auto limit = parse_number<std::uint64_t>(text)) memory = std::min(memory, *limit);
    }
  }
  return memory;
}

}  // namespace voxd::server
