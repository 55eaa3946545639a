#include "engine/core/error.hpp"

namespace nf {

void fail_check(const char* condition, const std::string& message, const char* file, int line) {
  throw InternalError(message + " (check '" + condition + "' failed at " + file + ":" + std::to_string(line) + ")");
}

}  // namespace nf
