#include "server/http/caller.h"

namespace voxd::server {
namespace {
thread_local Caller current;
}  // namespace

const Caller& current_caller() { return current; }
void set_current_caller(Caller caller) { current = std::move(caller); }

}  // namespace voxd::server
