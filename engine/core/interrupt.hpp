#pragma once
// Ctrl-C (SIGINT) and SIGTERM as a request to stop cleanly: the first one sets a flag that long
// loops poll (so a stage can save a checkpoint and say how to resume); a second one ends the
// process at once, as a user pressing Ctrl-C twice expects.
#include <string>

#include "engine/core/error.hpp"

namespace nf {

// Installs the handlers (idempotent). Commands that run long work call it once at start.
void install_interrupt_handler();
bool interrupted();
// For tests: sets or clears the flag as a signal would (as SIGINT).
void set_interrupted(bool value);
// The exit code of a run stopped on request: 128 + the signal (130 for SIGINT, 143 for SIGTERM).
int interrupted_exit_code();

// A file-size limit (ulimit -f) must not kill the process with SIGXFSZ: with the signal ignored a
// write past it fails with EFBIG, and the writer names the file and removes its partial copy.
void ignore_file_size_signal();

// Thrown by a stage that stopped on request; the CLI exits with interrupted_exit_code().
class Interrupted : public Error {
 public:
  explicit Interrupted(const std::string& message) : Error(ExitCode::Interrupted, message) {}
};

// How a command that threw ends: its exit code and its line for the user, the same for every
// exception wherever it is caught (the CLI, a batch task). `kind` is "" for a stop on request,
// "error" for bad input, usage, the device and filesystem errors (a folder or file the user named
// that cannot be read or written is bad input, not a bug), "internal error" for anything else.
struct Failure {
  int exit_code;
  std::string kind;
  std::string message;
  std::string line() const { return kind.empty() ? message : kind + ": " + message; }
};
// Call inside a catch block (it rethrows the current exception to classify it).
Failure current_failure();

// Throws Interrupted("<what>: stopped; ...") when a stop was asked: for work with nothing to resume
// (edit, pose, export), whose writers remove their partial files as the exception passes.
void stop_if_interrupted(const std::string& what);

}  // namespace nf
