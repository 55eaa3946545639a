#pragma once
// Typed errors. Each carries the process exit code the CLI returns for it (README, Exit codes):
// 1 bad input (the message names the file, field or value), 2 usage, 3 device or internal error,
// 130 stopped by Ctrl-C (128 + SIGINT, as shells report it).
#include <stdexcept>
#include <string>

namespace nf {

enum class ExitCode : int { Ok = 0, BadInput = 1, Usage = 2, DeviceOrInternal = 3, Interrupted = 130 };

class Error : public std::runtime_error {
 public:
  Error(ExitCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ExitCode code() const { return code_; }

 private:
  ExitCode code_;
};

// Bad user input: a file, field or value the user can fix.
class InputError : public Error {
 public:
  explicit InputError(const std::string& message) : Error(ExitCode::BadInput, message) {}
};

// Wrong command-line usage.
class UsageError : public Error {
 public:
  explicit UsageError(const std::string& message) : Error(ExitCode::Usage, message) {}
};

// The Vulkan device or driver failed, or a device limit was exceeded.
class DeviceError : public Error {
 public:
  explicit DeviceError(const std::string& message) : Error(ExitCode::DeviceOrInternal, message) {}
};

// A request larger than the device allows: memory, one allocation, one binding's range, a dispatch's
// workgroup count. The fix is a smaller setting (the pipeline names the stage's).
class DeviceLimitError : public DeviceError {
 public:
  explicit DeviceLimitError(const std::string& message) : DeviceError(message) {}
};

// The device stopped working (VK_ERROR_DEVICE_LOST: a driver reset, a GPU fault or a hung kernel).
// Nothing on it can be used any more; a new process can resume from the last checkpoint.
class DeviceLostError : public DeviceError {
 public:
  explicit DeviceLostError(const std::string& message) : DeviceError(message) {}
};

// A broken invariant inside nf_gpu: always a bug.
class InternalError : public Error {
 public:
  explicit InternalError(const std::string& message) : Error(ExitCode::DeviceOrInternal, message) {}
};

// Throws InternalError naming the failed condition and its location.
[[noreturn]] void fail_check(const char* condition, const std::string& message, const char* file, int line);

}  // namespace nf

// NF_CHECK(cond, msg): internal invariant; msg may be any expression convertible to std::string.
#define NF_CHECK(cond, msg)                                      \
  do {                                                           \
    if (!(cond)) ::nf::fail_check(#cond, (msg), __FILE__, __LINE__); \
  } while (0)
