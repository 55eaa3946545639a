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
// For tests: sets or clears the flag as a signal would.
void set_interrupted(bool value);

// Thrown by a stage that stopped on request; the CLI exits with 130 (128 + SIGINT).
class Interrupted : public Error {
 public:
  explicit Interrupted(const std::string& message) : Error(ExitCode::Interrupted, message) {}
};

}  // namespace nf
