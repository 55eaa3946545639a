#include "engine/knowledge/vlm_client.hpp"

#include <curl/curl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <thread>

#include "engine/core/error.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/core/log.hpp"
#include "engine/core/text.hpp"
#include "engine/io/json_fields.hpp"

namespace nf::knowledge {
namespace {

void init_curl_once() {
  static const bool done = [] {
    curl_global_init(CURL_GLOBAL_DEFAULT);
    return true;
  }();
  (void)done;
}

struct Transfer {
  std::string body;
  std::size_t limit = 0;
  bool too_large = false;
  double retry_after_s = -1;
};

std::size_t on_body(char* data, std::size_t size, std::size_t count, void* user) {
  auto* t = static_cast<Transfer*>(user);
  const std::size_t n = size * count;
  if (t->body.size() + n > t->limit) {
    t->too_large = true;
    return 0;  // aborts the transfer (CURLE_WRITE_ERROR)
  }
  t->body.append(data, n);
  return n;
}

std::size_t on_header(char* data, std::size_t size, std::size_t count, void* user) {
  auto* t = static_cast<Transfer*>(user);
  const std::string line(data, size * count);
  static const std::string kRetry = "retry-after:";
  if (to_lower(line.substr(0, kRetry.size())) == kRetry) {
    try {
      t->retry_after_s = std::stod(line.substr(kRetry.size()));
    } catch (...) {  // an HTTP date: fall back to our own back-off
    }
  }
  return size * count;
}

int on_progress(void*, curl_off_t, curl_off_t, curl_off_t, curl_off_t) { return interrupted() ? 1 : 0; }

// Server answers nest no deeper than this; a deeper one is refused before anything copies it.
constexpr int kMaxReplyDepth = 32;

// The server's own explanation, from an OpenAI-style {"error": {"message": ...}} or the raw text:
// the key masked first, then shortened at a character boundary.
std::string server_message(const std::string& body, const std::string& api_key) {
  std::string text = body;
  if (const std::optional<json> j = io::parse_json_bounded(body, kMaxReplyDepth); j && j->is_object() && j->contains("error")) {
    const json& e = (*j)["error"];
    text = e.is_object() && e.contains("message") && e["message"].is_string() ? e["message"].get<std::string>()
           : e.is_string()                                                      ? e.get<std::string>()
                                                                                : std::string("(an error without a message)");
  }
  text = shorten(mask_secret(text, api_key), 300);
  return text.empty() ? "(no message)" : text;
}

void sleep_interruptible(double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (interrupted()) throw Interrupted("knowledge: stopped while waiting to retry the VLM request");
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

ChatReply parse_reply(const std::string& body, const std::string& where, const std::string& api_key) {
  const std::optional<json> parsed = io::parse_json_bounded(body, kMaxReplyDepth);
  if (!parsed)
    throw InputError(where + ": the answer is not JSON (or nests deeper than " + std::to_string(kMaxReplyDepth) +
                     " levels), so this is not an OpenAI-compatible chat-completions endpoint (the answer begins: '" +
                     shorten(server_message(body, api_key), 120) + "')");
  const json& j = *parsed;
  if (!j.is_object() || !j.contains("choices") || !j["choices"].is_array() || j["choices"].empty())
    throw InputError(where + ": the answer has no 'choices' (not an OpenAI chat-completions answer): " +
                     server_message(body, api_key));
  const json& choice = j["choices"][0];
  if (!choice.is_object() || !choice.contains("message") || !choice["message"].is_object() || !choice["message"].contains("content"))
    throw InputError(where + ": the answer's choices[0] has no message.content");
  ChatReply reply;
  const json& content = choice["message"]["content"];
  if (content.is_string()) {
    reply.content = content.get<std::string>();
  } else if (content.is_array()) {  // content parts
    for (const json& part : content)
      if (part.is_object() && part.value("type", std::string()) == "text" && part.contains("text") && part["text"].is_string())
        reply.content += part["text"].get<std::string>();
  } else if (!content.is_null()) {
    throw InputError(where + ": message.content is neither text nor a list of parts");
  }
  if (choice.contains("finish_reason") && choice["finish_reason"].is_string())
    reply.finish_reason = shorten(choice["finish_reason"].get<std::string>(), 40);
  // Token counts only: a flat object of numbers.
  if (j.contains("usage") && j["usage"].is_object()) {
    reply.usage = json::object();
    for (const auto& [key, value] : j["usage"].items())
      if (value.is_number() && key.size() < 64) reply.usage[key] = value;
  }
  return reply;
}

}  // namespace

std::string mask_secret(std::string text, const std::string& secret) {
  if (secret.size() >= 4)
    for (std::size_t at; (at = text.find(secret)) != std::string::npos;) text.replace(at, secret.size(), "***");
  return text;
}

std::string chat_completions_url(const std::string& url) {
  if (url.rfind("http://", 0) != 0 && url.rfind("https://", 0) != 0)
    throw UsageError("knowledge.vlm = '" + redacted_url(url) + "': expected an http:// or https:// URL, e.g. "
                     "https://api.openai.com/v1 or http://localhost:11434 (Ollama)");
  std::string u = url;
  while (!u.empty() && u.back() == '/') u.pop_back();
  const auto ends_with = [&](const std::string& tail) { return u.size() >= tail.size() && u.compare(u.size() - tail.size(), tail.size(), tail) == 0; };
  if (ends_with("/chat/completions")) return u;
  if (ends_with("/v1")) return u + "/chat/completions";
  return u + "/v1/chat/completions";
}

std::string redacted_url(const std::string& url) {
  std::string u = url.substr(0, url.find_first_of("?#"));
  const std::size_t scheme = u.find("://");
  const std::size_t start = scheme == std::string::npos ? 0 : scheme + 3;
  const std::size_t slash = u.find('/', start);
  const std::size_t at = u.rfind('@', slash == std::string::npos ? u.size() : slash);
  if (at != std::string::npos && at >= start) u.erase(start, at + 1 - start);
  return u;
}

json chat_request_body(const VlmEndpoint& e, const json& messages) {
  json body{{"model", e.model}, {"messages", messages}, {"stream", false}};
  if (e.temperature >= 0) body["temperature"] = e.temperature;
  return body;
}

ChatReply chat_completion(const VlmEndpoint& e, const json& messages) {
  init_curl_once();
  const std::string url = chat_completions_url(e.url);
  const std::string where = "VLM endpoint " + redacted_url(url) + " (model '" + e.model + "')";
  // Invalid UTF-8 cannot come from our own messages; replace rather than fail if it ever does.
  const std::string request = dump_text(chat_request_body(e, messages));
  for (const char c : e.api_key)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      throw InputError("NF_VLM_API_KEY holds a control character (a line break pasted with it?)");

  std::unique_ptr<CURL, decltype(&curl_easy_cleanup)> curl(curl_easy_init(), curl_easy_cleanup);
  if (!curl) throw InternalError("curl_easy_init failed");
  curl_slist* headers = nullptr;
  headers = curl_slist_append(headers, "Content-Type: application/json");
  headers = curl_slist_append(headers, "Accept: application/json");
  if (!e.api_key.empty()) headers = curl_slist_append(headers, ("Authorization: Bearer " + e.api_key).c_str());
  std::unique_ptr<curl_slist, decltype(&curl_slist_free_all)> header_list(headers, curl_slist_free_all);

  const long timeout_ms = long(std::max(1.0, e.timeout_s * 1000.0));
  for (int attempt = 0;; ++attempt) {
    if (interrupted()) throw Interrupted("knowledge: stopped before the VLM request");
    Transfer t;
    t.limit = e.max_answer_bytes;
    CURL* c = curl.get();
    curl_easy_reset(c);
    curl_easy_setopt(c, CURLOPT_URL, url.c_str());
    curl_easy_setopt(c, CURLOPT_HTTPHEADER, header_list.get());
    curl_easy_setopt(c, CURLOPT_POSTFIELDS, request.data());
    curl_easy_setopt(c, CURLOPT_POSTFIELDSIZE_LARGE, curl_off_t(request.size()));
    curl_easy_setopt(c, CURLOPT_TIMEOUT_MS, timeout_ms);
    curl_easy_setopt(c, CURLOPT_CONNECTTIMEOUT_MS, std::min(timeout_ms, 15000L));
    curl_easy_setopt(c, CURLOPT_NOSIGNAL, 1L);
    curl_easy_setopt(c, CURLOPT_ACCEPT_ENCODING, "");
    curl_easy_setopt(c, CURLOPT_MAXFILESIZE_LARGE, curl_off_t(e.max_answer_bytes));
    curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, on_body);
    curl_easy_setopt(c, CURLOPT_WRITEDATA, &t);
    curl_easy_setopt(c, CURLOPT_HEADERFUNCTION, on_header);
    curl_easy_setopt(c, CURLOPT_HEADERDATA, &t);
    curl_easy_setopt(c, CURLOPT_NOPROGRESS, 0L);
    curl_easy_setopt(c, CURLOPT_XFERINFOFUNCTION, on_progress);

    const CURLcode code = curl_easy_perform(c);
    long status = 0;
    curl_easy_getinfo(c, CURLINFO_RESPONSE_CODE, &status);
    if (code == CURLE_ABORTED_BY_CALLBACK) throw Interrupted("knowledge: stopped during the VLM request");
    if (t.too_large || code == CURLE_FILESIZE_EXCEEDED)
      throw InputError(where + ": the answer is larger than " + std::to_string(e.max_answer_bytes >> 10) +
                       " KiB and was refused (knowledge.max_answer_mb raises the limit)");

    std::string failure;
    bool transient = false;
    if (code != CURLE_OK) {
      failure = curl_easy_strerror(code);
      transient = code == CURLE_COULDNT_CONNECT || code == CURLE_OPERATION_TIMEDOUT || code == CURLE_RECV_ERROR ||
                  code == CURLE_SEND_ERROR || code == CURLE_GOT_NOTHING || code == CURLE_PARTIAL_FILE ||
                  code == CURLE_COULDNT_RESOLVE_HOST;
      if (code == CURLE_OPERATION_TIMEDOUT)
        failure = "no complete answer within " + std::to_string(int(std::lround(e.timeout_s))) + " s (knowledge.timeout_s)";
      if (code == CURLE_COULDNT_CONNECT) failure += " (is the server running? Ollama: `ollama serve`)";
    } else if (status == 200) {
      ChatReply reply = parse_reply(t.body, where, e.api_key);
      reply.attempts = attempt + 1;
      reply.request_bytes = request.size();
      reply.answer_bytes = t.body.size();
      return reply;
    } else if (status == 401 || status == 403) {
      throw InputError(where + ": HTTP " + std::to_string(status) + ", the server refused the API key (" +
                       server_message(t.body, e.api_key) + "); set NF_VLM_API_KEY to a valid key");
    } else if (status == 404) {
      throw InputError(where + ": HTTP 404, no such endpoint or model (" + server_message(t.body, e.api_key) +
                       "); check knowledge.vlm (the server's base URL, e.g. http://localhost:11434) and knowledge.model "
                       "(Ollama: `ollama pull " + e.model + "`)");
    } else if (status == 429 || status >= 500) {
      failure = "HTTP " + std::to_string(status) + " (" + server_message(t.body, e.api_key) + ")";
      transient = true;
    } else {
      throw InputError(where + ": HTTP " + std::to_string(status) + ": " + server_message(t.body, e.api_key) +
                       (status == 400 ? " (does the model accept images?)" : ""));
    }
    if (!transient || attempt >= e.retries)
      throw InputError(where + ": " + failure + (attempt > 0 ? " after " + std::to_string(attempt + 1) + " attempts" : ""));
    const double wait = std::min(60.0, std::max(t.retry_after_s, e.retry_wait_s * std::pow(2.0, attempt)));
    log::warn("knowledge: ", where, ": ", failure, "; retrying in ", wait, " s (", attempt + 1, " of ", e.retries, ")");
    sleep_interruptible(wait);
  }
}

}  // namespace nf::knowledge
