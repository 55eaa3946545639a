#include "engine/core/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace nf {

unsigned cpu_threads() {
  if (const char* text = std::getenv("NF_THREADS")) {
    char* end = nullptr;
    const long v = std::strtol(text, &end, 10);
    if (end != text && *end == '\0' && v > 0) return unsigned(std::min<long>(v, 4096));
  }
  return std::max(1u, std::thread::hardware_concurrency());
}

void parallel_for(std::size_t count, const std::function<void(std::size_t, std::size_t)>& body, std::size_t min_per_thread) {
  const std::size_t threads = std::max<std::size_t>(1, std::min<std::size_t>(cpu_threads(), count / std::max<std::size_t>(1, min_per_thread) + 1));
  std::vector<std::thread> pool;
  std::vector<std::exception_ptr> errors(threads);
  const std::size_t chunk = (count + threads - 1) / threads;
  try {
    for (std::size_t t = 0; t < threads; ++t) {
      const std::size_t begin = t * chunk, end = std::min(count, begin + chunk);
      if (begin < end)
        pool.emplace_back([&, t, begin, end] {
          try {
            body(begin, end);
          } catch (...) {
            errors[t] = std::current_exception();  // rethrown on the calling thread
          }
        });
    }
  } catch (...) {
    for (auto& th : pool) th.join();
    throw;
  }
  for (auto& th : pool) th.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

void for_each_dynamic(int count, const std::function<void(int)>& body) {
  const int threads = std::max(1, std::min<int>(int(cpu_threads()), count));
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  const auto worker = [&] {
    for (int k = next++; k < count; k = next++) {
      try {
        body(k);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = count;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace nf
