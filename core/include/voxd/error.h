#pragma once
// Typed errors of the engine. Every failure a user can cause (bad upload, bad
// parameters, limits) is reported as voxd::Error with a code the API layer maps
// to an HTTP status, and a message written for the person who has to fix it.
#include <stdexcept>
#include <string>

namespace voxd {

enum class ErrorCode {
  invalid_argument,        // a parameter is out of range or inconsistent
  empty_input,             // zero bytes uploaded
  truncated_input,         // the data ends before its own header says it should
  malformed_input,         // syntax error in a text format, bad record in a binary one
  non_finite_coordinates,  // NaN or Inf in vertex data
  no_usable_triangles,     // parsed fine, but nothing to voxelize
  unknown_format,          // content matches no supported mesh format
  limit_exceeded,          // bytes, triangles or voxels over a configured limit
  cancelled,               // the job was cancelled while running
  io_error,                // reading or writing a file failed (keep it last: api/error_table.cpp checks every code has a row)
};

const char* to_string(ErrorCode code) noexcept;

class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ErrorCode code() const noexcept { return code_; }

 private:
  ErrorCode code_;
};

}  // namespace voxd
