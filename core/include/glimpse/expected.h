// Errors across module borders are values: Expected<T> holds a T or an Error with a message.
// core/ never throws across its API; the server maps ErrorCode to gRPC status codes in one place.
#pragma once

#include <cassert>
#include <functional>
#include <string>
#include <utility>
#include <variant>

namespace glimpse {

enum class ErrorCode {
  kInvalidArgument,     // malformed input: NaNs, too few points, unknown method, bad parameters
  kNotFound,            // a file, model or category that does not exist
  kResourceExhausted,   // a configured limit was exceeded
  kFailedPrecondition,  // the call is valid but the state does not allow it (e.g. untrained model)
  kDataLoss,            // corrupt or truncated bytes (model blobs, files)
  kCancelled,           // the caller asked to stop
  kInternal,            // a bug or a library failure we could not attribute to the input
};

const char* to_string(ErrorCode code);

struct Error {
  ErrorCode code = ErrorCode::kInternal;
  std::string message;
};

inline Error invalid_argument(std::string m) { return {ErrorCode::kInvalidArgument, std::move(m)}; }
inline Error not_found(std::string m) { return {ErrorCode::kNotFound, std::move(m)}; }
inline Error resource_exhausted(std::string m) { return {ErrorCode::kResourceExhausted, std::move(m)}; }
inline Error failed_precondition(std::string m) { return {ErrorCode::kFailedPrecondition, std::move(m)}; }
inline Error data_loss(std::string m) { return {ErrorCode::kDataLoss, std::move(m)}; }
inline Error cancelled(std::string m) { return {ErrorCode::kCancelled, std::move(m)}; }
inline Error internal_error(std::string m) { return {ErrorCode::kInternal, std::move(m)}; }

// Long work polls one of these (thread-safe) and stops with kCancelled when it returns true: a client
// that went away or a deadline that passed. An empty function never cancels.
using CancelFn = std::function<bool()>;

template <class T>
class [[nodiscard]] Expected {
 public:
  Expected(T value) : v_(std::move(value)) {}          // NOLINT: implicit on purpose
  Expected(Error error) : v_(std::move(error)) {}      // NOLINT: implicit on purpose

  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }

  T& value() & { assert(ok()); return std::get<0>(v_); }
  const T& value() const& { assert(ok()); return std::get<0>(v_); }
  T&& value() && { assert(ok()); return std::get<0>(std::move(v_)); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  T&& operator*() && { return std::move(*this).value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

  const Error& error() const { assert(!ok()); return std::get<1>(v_); }

 private:
  std::variant<T, Error> v_;
};

// A status: success or an Error.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : error_(std::move(error)), ok_(false) {}  // NOLINT: implicit on purpose
  bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  const Error& error() const { assert(!ok_); return error_; }

 private:
  Error error_;
  bool ok_ = true;
};

}  // namespace glimpse
