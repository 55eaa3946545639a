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

// Throws Interrupted("<what>: stopped; ...") when a stop was asked: for work with nothing to resume
// (edit, pose, export), whose writers remove their partial files as the exception passes.
void stop_if_interrupted(const std::string& what);

}  // namespace nf
