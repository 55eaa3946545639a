#pragma once
// A client for any OpenAI-compatible chat-completions endpoint (OpenAI, Ollama, llama.cpp's server,
// vLLM...), over libcurl. One call = one POST of the whole conversation; the answer's text comes
// back. Transient failures (HTTP 429 and 5xx, refused connections, timeouts) are retried with
// exponential back-off (a server's Retry-After is honoured); a refused key (401/403), a wrong URL
// or model (404) and other 4xx end at once in an InputError that says what to change. Answers
// larger than the limit are cut off and refused. The API key goes into the Authorization header
// only: it is never part of an error message, a log line or anything returned here.
#include <cstddef>
#include <string>

#include "engine/core/json.hpp"

namespace nf::knowledge {

struct VlmEndpoint {
  std::string url;    // as the user gave it: base, .../v1, or .../v1/chat/completions
  std::string model;  // e.g. gpt-4o, llava, qwen2.5vl
  std::string api_key;  // NF_VLM_API_KEY; empty: no Authorization header (a local server)
  double timeout_s = 180;        // whole request, per attempt
  int retries = 4;               // further attempts after a transient failure
  double retry_wait_s = 2;       // first back-off, doubled each retry, at most 60 s
  std::size_t max_answer_bytes = std::size_t(8) << 20;
  double temperature = -1;       // < 0: not sent (the server's default)
};

// The chat-completions URL for what the user typed ("http://localhost:11434" ->
// "http://localhost:11434/v1/chat/completions"). UsageError when it is not http(s).
std::string chat_completions_url(const std::string& url);
// `text` with every occurrence of `secret` (the API key) replaced by "***": for anything a server
// sends back that reaches a message, a log or a file.
std::string mask_secret(std::string text, const std::string& secret);
// The URL without user name, password or query (which may hold a key): for logs and transcripts.
std::string redacted_url(const std::string& url);

struct ChatReply {
  std::string content;        // the assistant's text
  std::string finish_reason;  // "stop", "length", ...
  json usage;                 // the server's token counts, when it sends them
  int attempts = 0;           // HTTP requests made (1 + retries used)
  std::size_t request_bytes = 0, answer_bytes = 0;
};

// The request body for `messages` (OpenAI format).
json chat_request_body(const VlmEndpoint& endpoint, const json& messages);

// POSTs the conversation and returns the reply. Throws InputError (naming the redacted URL, the
// status and the server's own message) when it cannot get one, and nf::Interrupted on Ctrl-C.
ChatReply chat_completion(const VlmEndpoint& endpoint, const json& messages);

}  // namespace nf::knowledge
