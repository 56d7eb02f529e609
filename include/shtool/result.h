// The runtime's one way of reporting what can fail on input (a table file, a lobe
// set): a value or an error message, never an exception. Everything else the runtime
// documents as a precondition (see docs/architecture.md).
#pragma once

#include <optional>
#include <string>
#include <utility>

namespace shtool {

struct Error {
  std::string message;  // names the input and the problem, e.g. "x.shtb: CRC-32 mismatch in array 'a' ..."
};

// Success without a value.
struct Ok {};

// Expected-style result. value() on an error, like error() on a value, is a
// precondition violation.
template <class T>
class Result {
 public:
  Result(T value) : value_(std::move(value)) {}
  Result(Error error) : error_(std::move(error)) {}
  bool ok() const { return value_.has_value(); }
  explicit operator bool() const { return ok(); }
  const T& value() const& { return *value_; }
  T& value() & { return *value_; }
  T&& value() && { return std::move(*value_); }
  const Error& error() const { return error_; }

 private:
  std::optional<T> value_;
  Error error_;
};

}  // namespace shtool
