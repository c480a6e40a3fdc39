#pragma once
// The part of a benchmark that bench/serial_fraction.sh counts under
// callgrind (run with --instr-atstart=no): the fixtures (the mesh, its
// voxels, a thickness map) are made uninstrumented, at native speed, before
// a section starts; a section counts from its start and dumps its counts,
// every thread's, under its name when it ends. Only a process's first section
// counts right: callgrind's zeroing misses threads that have ended, and
// threads started after instrumentation is turned on again are missed, so
// the script runs a process per benchmark. Outside valgrind the marks are a
// few instructions each; where valgrind's header is missing, nothing.
#include <string>

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define VOXD_CALLGRIND_MARKS 1
#endif

namespace voxd::bench {

class CallgrindSection {
 public:
  explicit CallgrindSection(std::string name) : name_(std::move(name)) {
#ifdef VOXD_CALLGRIND_MARKS
    CALLGRIND_START_INSTRUMENTATION;
    CALLGRIND_ZERO_STATS;
#endif
  }
  ~CallgrindSection() {
#ifdef VOXD_CALLGRIND_MARKS
    CALLGRIND_DUMP_STATS_AT(name_.c_str());
    CALLGRIND_STOP_INSTRUMENTATION;
#endif
  }
  CallgrindSection(const CallgrindSection&) = delete;
  CallgrindSection& operator=(const CallgrindSection&) = delete;

 private:
  std::string name_;
};

}  // namespace voxd::bench
