#pragma once
// Small statistics used by benchmarks and checks.
#include <vector>

namespace nf {

double median(std::vector<double> values);  // 0 for an empty input
double minimum(const std::vector<double>& values);
double maximum(const std::vector<double>& values);

}  // namespace nf
