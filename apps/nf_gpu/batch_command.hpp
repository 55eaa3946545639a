#pragma once
// `nf_gpu batch run|task|status|report`: the CLI of engine/batch (its options and what it prints).
#include <CLI/CLI.hpp>

#include <memory>

namespace nf_cli {

class BatchCommand {
 public:
  explicit BatchCommand(CLI::App& app);
  bool parsed() const { return command_->parsed(); }
  int run() const;

 private:
  CLI::App* command_ = nullptr;
  CLI::App *run_ = nullptr, *task_ = nullptr, *status_ = nullptr, *report_ = nullptr;
  struct Values;
  std::shared_ptr<Values> v_;
};

}  // namespace nf_cli
