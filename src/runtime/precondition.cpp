#include "precondition.h"

#include <cstdio>
#include <cstdlib>
#include <new>
#include <stdexcept>

namespace shtool::detail {

#if defined(__cpp_exceptions)
void precondition_failed(const std::string& message) { throw std::invalid_argument(message); }
void invariant_failed(const std::string& message) { throw std::logic_error(message); }
void dependency_failed(const std::string& message) { throw std::runtime_error(message); }
void allocation_failed() { throw std::bad_alloc(); }
#else
namespace {
[[noreturn]] void abort_with(const char* kind, const std::string& message) {
  std::fprintf(stderr, "shtool runtime: %s: %s\n", kind, message.c_str());
  std::abort();
}
}  // namespace

void precondition_failed(const std::string& message) { abort_with("precondition violated", message); }
void invariant_failed(const std::string& message) { abort_with("internal error", message); }
void dependency_failed(const std::string& message) { abort_with("dependency failed", message); }
void allocation_failed() { abort_with("out of memory", "allocation failed"); }
#endif

}  // namespace shtool::detail
