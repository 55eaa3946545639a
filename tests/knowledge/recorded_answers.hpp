#pragma once
// Recorded VLM answers for the knowledge tests, and which prompt a conversation is at (from its last
// user message), so a scripted model can answer whatever the client asks in whatever order.
#include <map>
#include <string>

#include "engine/core/json.hpp"

namespace nf::test {

// The step the last user message asks: length, thickness, verify, direction, eyes, hair, body, or retry.
inline std::string prompt_step(const json& messages) {
  std::string text;
  for (const json& m : messages)
    if (m.value("role", std::string()) == "user") {
      text.clear();
      if (m["content"].is_string()) text = m["content"].get<std::string>();
      else
        for (const json& part : m["content"])
          if (part.value("type", std::string()) == "text") text += part["text"].get<std::string>();
    }
  if (text.find("could not use that answer") != std::string::npos) return "retry";
  if (text.find("estimate the accurate fur length") != std::string::npos) return "length";
  if (text.find("effective fur thickness") != std::string::npos) return "thickness";
  if (text.find("Are you sure") != std::string::npos) return "verify";
  if (text.find("fur growing direction") != std::string::npos) return "direction";
  if (text.find("distance between eyeballs") != std::string::npos) return "eyes";
  if (text.find("diameter of a single hair") != std::string::npos) return "hair";
  if (text.find("head-and-body length") != std::string::npos) return "body";
  return "unknown";
}

// The prompt a retry asks again: the step of the conversation before its retries.
inline std::string asked_step(json messages) {
  while (!messages.empty() && prompt_step(messages) == "retry") messages.erase(messages.size() - 1);
  return prompt_step(messages);
}

// A careful model: plain JSON for every prompt (a cat with a mane, to see mane kept).
inline std::map<std::string, std::string> good_answers() {
  return {
      {"length", R"({"leg_front": 0.8, "leg_rear": 0.9, "paws": 0.45, "front_paws": 0.45, "belly": 1.25, "neck": 1.2,
                   "face": 0.5, "ears": 0.3, "under_tail": 1.0, "tail": 1.35, "body": 1.0, "paw_pads": 0.1,
                   "inner_earcanal": 0.15, "eyes": 0, "nosetip": 0, "mane": 3.0})"},
      {"thickness", R"({"leg_front": 0.3, "leg_rear": 0.3, "paws": 0.15, "front_paws": 0.15, "belly": 0.4, "neck": 0.4,
                      "face": 0.2, "ears": 0.1, "under_tail": 0.35, "tail": 0.5, "body": 0.35, "paw_pads": 0.0,
                      "inner_earcanal": 0.05, "eyes": 0, "nosetip": 0, "mane": 1.0})"},
      {"verify", R"({"length": {"body": 1.1, "tail": 1.4}, "thickness": {"body": 0.4}})"},
      {"direction", R"({"leg_front": [0, -1, 0], "leg_rear": [0, -1, 0], "paws": [0, -0.6, 0.8], "front_paws": [0, -0.6, 0.8],
                      "belly": [0, -0.9, -0.45], "neck": [0, -0.5, -0.86], "face": [0, 0.24, -0.97], "ears": [0, 1, 0],
                      "under_tail": [0, -1, -0.2], "tail": [0, -0.2, -1], "body": [0, -0.33, -0.94], "paw_pads": [0, -1, 0],
                      "inner_earcanal": [0, 1, 0], "eyes": [0, 0, 1], "nosetip": [0, 0, 1], "mane": [0, -0.7, -0.7]})"},
      {"eyes", R"({"eye_distance_cm": 3.2})"},
      {"hair", R"({"hair_diameter_mm": 0.06})"},
      {"body", R"({"body_length_cm": 46})"},
  };
}

// An OpenAI chat-completions answer carrying `content`.
inline std::string chat_answer(const std::string& content, const std::string& finish = "stop") {
  return json{{"id", "chatcmpl-test"},
              {"object", "chat.completion"},
              {"choices", json::array({{{"index", 0}, {"message", {{"role", "assistant"}, {"content", content}}}, {"finish_reason", finish}}})},
              {"usage", {{"prompt_tokens", 1000}, {"completion_tokens", 200}}}}
      .dump();
}

}  // namespace nf::test
