#pragma once
// Progress for long commands: a redrawn bar on a terminal, a plain line every few seconds otherwise
// (logs and CI stay readable).
#include <chrono>
#include <cstdint>
#include <string>

namespace nf {

class Progress {
 public:
  Progress(std::string label, std::uint64_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // Sets the completed count and an optional status text (e.g. "loss 0.013 psnr 27.1").
  void update(std::uint64_t done, const std::string& status = "");
  void finish(const std::string& status = "");
  // The last line of a run stopped early: the count reached, not the total.
  void stop(const std::string& status);

 private:
  void draw(bool final_line);

  std::string label_;
  std::uint64_t total_;
  std::uint64_t done_ = 0;
  std::string status_;
  bool tty_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace nf
