#include "engine/core/interrupt.hpp"

#include <atomic>
#include <csignal>
#include <filesystem>

namespace nf {
namespace {

std::atomic<bool> g_interrupted{false};
std::atomic<int> g_signal{SIGINT};

// The first SIGINT or SIGTERM asks for a clean stop; a second one of either kind ends the process
// with the default action (signal and raise are async-signal-safe, as are lock-free atomics).
extern "C" void on_interrupt(int sig) {
  if (!g_interrupted.load()) g_signal.store(sig);
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

void set_interrupted(bool value) {
  g_signal.store(SIGINT);
  g_interrupted.store(value);
}

int interrupted_exit_code() { return 128 + g_signal.load(); }

void stop_if_interrupted(const std::string& what) {
  if (interrupted())
    throw Interrupted(what + ": stopped on request; no partial file is left, but files this run had finished may sit beside an earlier "
                      "run's: run the command again to complete it");
}

Failure current_failure() {
  try {
    throw;
  } catch (const Interrupted& e) {
    return {interrupted_exit_code(), "", e.what()};
  } catch (const Error& e) {
    return {int(e.code()), "error", e.what()};
  } catch (const std::filesystem::filesystem_error& e) {
    return {int(ExitCode::BadInput), "error", (e.path1().empty() ? "" : e.path1().string() + ": ") + e.code().message()};
  } catch (const std::exception& e) {
    return {int(ExitCode::DeviceOrInternal), "internal error", e.what()};
  }
}

void ignore_file_size_signal() {
  struct sigaction action {};
  action.sa_handler = SIG_IGN;
  sigemptyset(&action.sa_mask);
  sigaction(SIGXFSZ, &action, nullptr);
}

}  // namespace nf
