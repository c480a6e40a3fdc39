#pragma once
// Parameter validation errors. Validation collects every offending field, each
// with its JSON path (RFC 6901 pointer, e.g. "/grid/resolution"), so a client
// can fix all of them in one round trip.
#include <stdexcept>
#include <string>
#include <vector>

namespace voxd::api {

struct FieldError {
  std::string path;     // JSON pointer into the job parameters
  std::string message;  // what is wrong and what is accepted
};

class InvalidParams : public std::runtime_error {
 public:
  explicit InvalidParams(std::vector<FieldError> errors);
  const std::vector<FieldError>& errors() const noexcept { return errors_; }

 private:
  std::vector<FieldError> errors_;
};

}  // namespace voxd::api
