#include "engine/core/progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace nf {

Progress::Progress(std::string label, std::uint64_t total)
    : label_(std::move(label)), total_(total), tty_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()), last_draw_(start_) {}

Progress::~Progress() {
  if (!finished_) finish();
}

void Progress::update(std::uint64_t done, const std::string& status) {
  done_ = done;
  status_ = status;
  const auto now = std::chrono::steady_clock::now();
  const auto interval = tty_ ? std::chrono::milliseconds(100) : std::chrono::milliseconds(5000);
  if (now - last_draw_ >= interval) {
    last_draw_ = now;
    draw(false);
  }
}

void Progress::finish(const std::string& status) {
  if (finished_) return;
  finished_ = true;
  done_ = total_;
  if (!status.empty()) status_ = status;
  draw(true);
}

void Progress::stop(const std::string& status) {
  if (finished_) return;
  finished_ = true;
  status_ = status;
  draw(true);
}

void Progress::draw(bool final_line) {
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double fraction = total_ ? double(done_) / double(total_) : 1.0;
  if (tty_) {
    constexpr int width = 30;
    const int filled = int(fraction * width + 0.5);
    std::fprintf(stderr, "\r%s [%.*s%*s] %3d%% %.1fs %s\x1b[K", label_.c_str(), filled,
                 "##############################", width - filled, "", int(fraction * 100), seconds,
                 status_.c_str());
    if (final_line) std::fputc('\n', stderr);
  } else {
    std::fprintf(stderr, "%s: %llu/%llu (%d%%) %.1fs %s\n", label_.c_str(), (unsigned long long)done_,
                 (unsigned long long)total_, int(fraction * 100), seconds, status_.c_str());
  }
  std::fflush(stderr);
}

}  // namespace nf
