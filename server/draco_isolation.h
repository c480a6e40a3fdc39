#pragma once
// Untrusted Draco decoded by libdraco in a short-lived child process (this
// same executable, `voxd decode-draco-isolated`), under a data-memory limit
// (RLIMIT_DATA: heap and anonymous mappings, where libdraco's buffers live),
// a CPU limit (RLIMIT_CPU) and a wall-clock deadline. libdraco is not ours:
// fuzzing found header counts that make it reserve tens of gigabytes; a
// crash, a hang or a runaway allocation now ends the child, and the request
// gets a 422, while the service and every other job go on.
// Under AddressSanitizer (whose shadow memory defeats rlimits) the child is
// bounded by ASan's own allocation limits instead.
#include <chrono>
#include <cstdint>
#include <span>
#include <string>

#include "voxd/mesh.h"
#include "voxd/mesh_io/mesh_decode.h"

namespace voxd::server {

struct DracoIsolation {
  std::string executable = "/proc/self/exe";
  std::uint64_t max_memory = std::uint64_t{2} << 30;  // the child's data segment
  int max_cpu_seconds = 30;
  std::chrono::seconds deadline{60};
  std::uint64_t max_triangles = 20'000'000;
};

// Decodes in a child; throws voxd::Error (malformed_input, limit_exceeded)
// with a message naming what went wrong, io_error if no child could run.
Mesh decode_draco_isolated(std::span<const std::uint8_t> data, const DracoIsolation& isolation);

// The child's side: `voxd decode-draco-isolated MAX_TRIANGLES MAX_MEMORY
// MAX_CPU_SECONDS`, Draco on standard input, the mesh on standard output.
int decode_draco_child(int argc, char** argv);

}  // namespace voxd::server
