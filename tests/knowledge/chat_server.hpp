#pragma once
// A loopback HTTP server that speaks the OpenAI chat-completions protocol (cpp-httplib), for the
// VLM client's tests: a `responder` decides each reply from the request, and every request and its
// Authorization header is kept for the test to inspect.
#include <httplib.h>

#include <chrono>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/json.hpp"

namespace nf::test {

struct HttpReply {
  int status = 200;
  std::string body;
  double delay_s = 0;  // sleep before answering (a server that never answers in time)
  std::map<std::string, std::string> headers;
};

inline HttpReply reply(int status, std::string body, double delay_s = 0, std::map<std::string, std::string> headers = {}) {
  HttpReply r;
  r.status = status, r.body = std::move(body), r.delay_s = delay_s, r.headers = std::move(headers);
  return r;
}

class ChatServer {
 public:
  using Responder = std::function<HttpReply(const json& request, int index)>;

  explicit ChatServer(Responder responder) : responder_(std::move(responder)) {
    server_.Post("/v1/chat/completions", [this](const httplib::Request& req, httplib::Response& res) {
      json body;
      try {
        body = json::parse(req.body);
      } catch (const json::exception&) {
        body = json();
      }
      int index = 0;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        index = int(requests_.size());
        requests_.push_back(body);
        authorizations_.push_back(req.get_header_value("Authorization"));
      }
      const HttpReply reply = responder_(body, index);
      if (reply.delay_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(reply.delay_s));
      res.status = reply.status;
      for (const auto& [k, v] : reply.headers) res.set_header(k, v);
      res.set_content(reply.body, "application/json");
    });
    port_ = server_.bind_to_any_port("127.0.0.1");
    thread_ = std::thread([this] { server_.listen_after_bind(); });
    for (int i = 0; i < 500 && !server_.is_running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ~ChatServer() {
    server_.stop();
    thread_.join();
  }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_); }
  std::vector<json> requests() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return requests_;
  }
  std::vector<std::string> authorizations() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return authorizations_;
  }

 private:
  Responder responder_;
  httplib::Server server_;
  std::thread thread_;
  int port_ = 0;
  mutable std::mutex mutex_;
  std::vector<json> requests_;
  std::vector<std::string> authorizations_;
};

}  // namespace nf::test
