#include "engine/knowledge/vlm_session.hpp"

#include <chrono>

#include "engine/core/atomic_file.hpp"
#include "engine/core/content_hash.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/io/json_fields.hpp"

namespace nf::knowledge {

VlmSession::VlmSession(VlmEndpoint endpoint, std::filesystem::path cache, const std::filesystem::path& transcript)
    : endpoint_(std::move(endpoint)), cache_(std::move(cache)), transcript_(transcript, std::ios::trunc) {
  std::filesystem::create_directories(cache_);
}

void VlmSession::forget_sample() {
  for (const std::filesystem::path& p : written_) std::filesystem::remove(p);
  written_.clear();
}

std::string VlmSession::chat(const json& messages, const std::string& step) {
  const std::string url = redacted_url(chat_completions_url(endpoint_.url));
  const std::string key = hash_bytes(dump_text(json{{"url", url}, {"model", endpoint_.model}, {"temperature", endpoint_.temperature},
                                                    {"sample", sample_}, {"messages", messages}}));
  const std::filesystem::path cached = cache_ / (key + ".json");
  json line{{"sample", sample_}, {"step", step}, {"url", url}, {"model", endpoint_.model}, {"messages", readable(messages)}};
  const auto start = std::chrono::steady_clock::now();
  ChatReply reply;
  bool hit = false;
  if (std::filesystem::exists(cached)) {
    try {
      const json j = io::read_json_file(cached);
      reply.content = j.at("answer").get<std::string>();
      reply.finish_reason = j.value("finish_reason", std::string());
      hit = true;
    } catch (const std::exception&) {  // a damaged cache entry is asked again
    }
  }
  if (!hit) {
    log::info("knowledge: asking ", endpoint_.model, " (", step, ", sample ", sample_ + 1, ")");
    try {
      reply = chat_completion(endpoint_, messages);
    } catch (const Error& e) {  // the failed request is part of the record too
      line["error"] = e.what();
      transcript_ << masked(dump_text(line)) << "\n" << std::flush;
      throw;
    }
    reply.content = masked(reply.content);
    write_file_atomic(cached, dump_text(json{{"answer", reply.content}, {"finish_reason", reply.finish_reason}}) + "\n");
    written_.push_back(cached);
    ++sent, request_bytes += reply.request_bytes, answer_bytes += reply.answer_bytes, attempts += reply.attempts;
  } else {
    ++from_cache;
  }
  if (reply.finish_reason == "length")
    warnings.push_back("the " + step + " answer was cut off at the model's token limit");
  line["cached"] = hit;
  line["answer"] = reply.content;
  line["finish_reason"] = reply.finish_reason;
  if (!hit) line["usage"] = reply.usage, line["attempts"] = reply.attempts, line["request_bytes"] = reply.request_bytes,
            line["answer_bytes"] = reply.answer_bytes;
  line["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  transcript_ << masked(dump_text(line)) << "\n" << std::flush;
  return reply.content;
}

json VlmSession::readable(const json& messages) const {
  json out = messages;
  for (json& m : out)
    if (m.contains("content") && m["content"].is_array())
      for (json& part : m["content"])
        if (part.value("type", std::string()) == "image_url") {
          const std::string url = part["image_url"].value("url", std::string());
          const auto it = labels_.find(url);
          part["image_url"]["url"] = it != labels_.end() ? it->second : "(image, " + std::to_string(url.size()) + " bytes)";
        }
  return out;
}

}  // namespace nf::knowledge
