#include "engine/core/interrupt.hpp"

#include <atomic>
#include <csignal>

namespace nf {
namespace {

std::atomic<bool> g_interrupted{false};

// The first SIGINT or SIGTERM asks for a clean stop; a second one of either kind ends the process
// with the default action (signal and raise are async-signal-safe).
extern "C" void on_interrupt(int sig) {
  if (g_interrupted.exchange(true)) {
    std::signal(sig, SIG_DFL);
    std::raise(sig);
  }
}

}  // namespace

void install_interrupt_handler() {
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool interrupted() { return g_interrupted.load(std::memory_order_relaxed); }

void set_interrupted(bool value) { g_interrupted.store(value); }

}  // namespace nf
