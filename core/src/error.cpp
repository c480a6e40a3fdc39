#include "voxd/error.h"

#include "voxd/progress.h"

namespace voxd {

const char* to_string(ErrorCode code) noexcept {
  switch (code) {
    case ErrorCode::invalid_argument: return "invalid_argument";
    case ErrorCode::empty_input: return "empty_input";
    case ErrorCode::truncated_input: return "truncated_input";
    case ErrorCode::malformed_input: return "malformed_input";
    case ErrorCode::non_finite_coordinates: return "non_finite_coordinates";
    case ErrorCode::no_usable_triangles: return "no_usable_triangles";
    case ErrorCode::unknown_format: return "unknown_format";
    case ErrorCode::limit_exceeded: return "limit_exceeded";
    case ErrorCode::cancelled: return "cancelled";
    case ErrorCode::io_error: return "io_error";
  }
  return "unknown";
}

void JobControl::check_cancelled() const {
  if (cancel_requested()) throw Error(ErrorCode::cancelled, "the job was cancelled");
}

}  // namespace voxd
