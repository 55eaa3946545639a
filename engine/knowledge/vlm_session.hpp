#pragma once
// A VLM annotation's requests: each answered from a cache when the same conversation was asked
// before, else sent, and either way one line of a transcript (the knowledge stage's).
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/knowledge/vlm_client.hpp"

namespace nf::knowledge {

// Every request of a VLM annotation goes through here: answered from the cache when the same
// conversation was asked before (images, prompts, model, sample), else sent; either way one line of
// the transcript. The API key is never in a line: images are named by file, and any echo of the key
// by a server is masked.
class VlmSession {
 public:
  VlmSession(VlmEndpoint endpoint, std::filesystem::path cache, const std::filesystem::path& transcript);
  // A conversation that ended in an error is not kept: a rerun asks the model again.
  void forget_sample();
  void keep_sample() { written_.clear(); }
  void name_image(const std::string& data_url, const std::string& label) { labels_[data_url] = label; }
  void set_sample(int sample) { sample_ = sample; }

  // The model's answer to `messages` (the cached one when the same conversation was asked before);
  // `step` names the request in the transcript and in warnings.
  std::string chat(const json& messages, const std::string& step);

  int sent = 0, from_cache = 0, attempts = 0;
  std::size_t request_bytes = 0, answer_bytes = 0;
  std::vector<std::string> warnings;

 private:
  // Messages with each image replaced by the file it was saved as.
  json readable(const json& messages) const;
  std::string masked(std::string text) const { return mask_secret(std::move(text), endpoint_.api_key); }

  VlmEndpoint endpoint_;
  std::filesystem::path cache_;
  std::ofstream transcript_;
  std::map<std::string, std::string> labels_;
  std::vector<std::filesystem::path> written_;  // cache entries of the current sample
  int sample_ = 0;
};

}  // namespace nf::knowledge
