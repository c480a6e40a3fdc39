#include "api/error_table.h"

#include <array>

namespace voxd::api {
namespace {

constexpr const char* kInvalidMesh = "invalid-mesh";
constexpr const char* kInvalidMeshTitle = "The mesh cannot be used";

constexpr std::array kTable{
    ErrorKind{ErrorCode::invalid_argument, "invalid-params", "Invalid job parameters", 422, kExitUsage, true},
    ErrorKind{ErrorCode::empty_input, kInvalidMesh, kInvalidMeshTitle, 422, kExitFailure, true},
    ErrorKind{ErrorCode::truncated_input, kInvalidMesh, kInvalidMeshTitle, 422, kExitFailure, true},
    ErrorKind{ErrorCode::malformed_input, kInvalidMesh, kInvalidMeshTitle, 422, kExitFailure, true},
    ErrorKind{ErrorCode::non_finite_coordinates, kInvalidMesh, kInvalidMeshTitle, 422, kExitFailure, true},
    ErrorKind{ErrorCode::no_usable_triangles, kInvalidMesh, kInvalidMeshTitle, 422, kExitFailure, true},
    ErrorKind{ErrorCode::unknown_format, "unsupported-format", "Unsupported mesh format", 415, kExitFailure, true},
    ErrorKind{ErrorCode::limit_exceeded, "limit-exceeded", "Over the service's limits", 422, kExitUsage, true},
    ErrorKind{ErrorCode::cancelled, "cancelled", "The job was cancelled", 409, kExitFailure, true},
    ErrorKind{ErrorCode::io_error, "internal", "Internal error", 500, kExitFailure, false},
};

// The table is indexed by the code: a new code without its row fails to build.
constexpr bool in_enum_order() {
  for (std::size_t i = 0; i < kTable.size(); ++i)
    if (static_cast<std::size_t>(kTable[i].code) != i) return false;
  return true;
}
static_assert(in_enum_order(), "error_table rows must follow voxd::ErrorCode's order");
static_assert(kTable.size() == static_cast<std::size_t>(ErrorCode::io_error) + 1, "every ErrorCode needs a row");

}  // namespace

std::span<const ErrorKind> error_table() { return kTable; }

const ErrorKind& error_kind(ErrorCode code) { return kTable[static_cast<std::size_t>(code)]; }

}  // namespace voxd::api
