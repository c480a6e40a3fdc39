#pragma once
// The one table of what an engine error means to a client: for every
// voxd::ErrorCode, the problem type (RFC 9457 slug and title), the HTTP
// status, and the CLI's exit status. The HTTP service, a job's failure record
// and the CLI all read it, so the three can never disagree.
//
// CLI exit statuses (README "Command line"): 2 for what the caller asked
// wrongly (a parameter, a limit the request goes over), 1 for everything else
// (the mesh, the file system, an internal failure).
#include <span>

#include "voxd/error.h"

namespace voxd::api {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;     // the input or the machine
inline constexpr int kExitUsage = 2;       // the request: a usage, parameter or limit error

struct ErrorKind {
  ErrorCode code;
  const char* slug;   // problem type: urn:voxd:problem:<slug>
  const char* title;  // the problem's title
  int http_status;
  int cli_exit;
  // Whether the message is the client's to read. An internal error's message
  // (a path, a system error) is logged, and the client gets a generic detail.
  bool client_message;
};

// Every code, in the enum's order.
std::span<const ErrorKind> error_table();
const ErrorKind& error_kind(ErrorCode code);

}  // namespace voxd::api
