#include "engine/core/finite.hpp"

#include <cmath>
#include <sstream>

#include "engine/core/error.hpp"

namespace nf {
namespace {

template <class T>
void check(std::span<const T> values, std::string_view what) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      std::ostringstream os;
      os << what << ": element " << i << " is " << values[i] << " (NaN and Inf are not accepted)";
      throw InputError(os.str());
    }
  }
}

}  // namespace

void require_finite(std::span<const float> values, std::string_view what) { check(values, what); }
void require_finite(std::span<const double> values, std::string_view what) { check(values, what); }

}  // namespace nf
