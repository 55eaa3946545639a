#pragma once
// NaN/Inf guards at the boundary: inputs are checked where they enter the engine, and a bad value
// is rejected with an error that names the input, the element and the value, never propagated.
#include <span>
#include <string_view>

namespace nf {

// Throws InputError("<what>: element i is nan") for the first non-finite value.
void require_finite(std::span<const float> values, std::string_view what);
void require_finite(std::span<const double> values, std::string_view what);

}  // namespace nf
