#include "engine/gradcheck/harness.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "engine/core/error.hpp"

namespace nf::gradcheck {
namespace {

template <class To, class From>
Arrays<To> cast(const Arrays<From>& a) {
  Arrays<To> out(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) out[i].assign(a[i].begin(), a[i].end());
  return out;
}

template <class T>
bool all_finite(const std::vector<T>& v) {
  return std::all_of(v.begin(), v.end(), [](T x) { return std::isfinite(double(x)); });
}

// Compares `got` with `expected` array by array and appends one row per array.
template <class A, class B>
void compare(std::vector<Row>& rows, const Row& base, const std::vector<std::string>& names, const Arrays<A>& got,
             const Arrays<B>& expected, double tolerance) {
  if (got.size() != expected.size())
    throw InternalError(base.kernel + ": " + base.check + " produced " + std::to_string(got.size()) +
                        " arrays, expected " + std::to_string(expected.size()));
  for (std::size_t a = 0; a < got.size(); ++a) {
    Row row = base;
    row.array = a < names.size() ? names[a] : "#" + std::to_string(a);
    row.tolerance = tolerance;
    if (got[a].size() != expected[a].size()) {
      row.pass = false;
      row.note = "size " + std::to_string(got[a].size()) + " != " + std::to_string(expected[a].size());
      rows.push_back(row);
      continue;
    }
    double scale = 0;
    for (const auto& x : expected[a]) scale = std::max(scale, std::fabs(double(x)));
    row.finite = all_finite(got[a]) && all_finite(expected[a]);
    for (std::size_t i = 0; i < got[a].size(); ++i)
      row.max_abs = std::max(row.max_abs, std::fabs(double(got[a][i]) - double(expected[a][i])));
    // Relative to the array's largest magnitude; an all-zero reference must be matched exactly
    // up to a denormal-sized floor.
    row.max_rel = row.max_abs / std::max(scale, 1e-30);
    row.pass = row.finite && (row.max_rel <= tolerance || row.max_abs <= 1e-30);
    rows.push_back(row);
  }
}

// As compare, for gradients against finite differences: arrays whose step is 0 were not probed and
// get a skipped row with the case's reason instead.
template <class A>
void compare_probed(std::vector<Row>& rows, const Row& base, const std::vector<std::string>& names,
                    const std::vector<double>& steps, const std::string& reason, const Arrays<A>& got,
                    const Arrays<double>& fd, double tolerance) {
  Arrays<A> probed_got;
  Arrays<double> probed_fd;
  std::vector<std::string> probed_names;
  for (std::size_t a = 0; a < names.size(); ++a) {
    if (steps[a] > 0) {
      probed_got.push_back(got[a]);
      probed_fd.push_back(fd[a]);
      probed_names.push_back(names[a]);
      continue;
    }
    Row skip = base;
    skip.array = names[a];
    skip.skipped = true;
    skip.note = reason.empty() ? "not probed" : reason;
    rows.push_back(skip);
  }
  if (!probed_names.empty()) compare(rows, base, probed_names, probed_got, probed_fd, tolerance);
}

double weighted_sum(const Arrays<double>& weights, const Arrays<double>& out) {
  double s = 0;
  for (std::size_t a = 0; a < out.size(); ++a)
    for (std::size_t i = 0; i < out[a].size(); ++i) s += weights[a][i] * out[a][i];
  return s;
}

// Central differences of L = sum w * f(in) over every input element.
template <class T, class Forward>
Arrays<double> finite_differences(const Arrays<T>& inputs, const std::vector<double>& steps,
                                  const Arrays<double>& weights, const Forward& forward) {
  Arrays<double> grad(inputs.size());
  Arrays<T> probe = inputs;
  for (std::size_t a = 0; a < inputs.size(); ++a) {
    grad[a].assign(inputs[a].size(), 0.0);
    if (!(steps[a] > 0)) continue;  // not probed (check 4 skips arrays float cannot resolve)
    for (std::size_t i = 0; i < inputs[a].size(); ++i) {
      const T x = inputs[a][i];
      probe[a][i] = T(double(x) + steps[a]);
      const T up = probe[a][i];
      const double plus = weighted_sum(weights, cast<double>(forward(probe)));
      probe[a][i] = T(double(x) - steps[a]);
      const T down = probe[a][i];
      const double minus = weighted_sum(weights, cast<double>(forward(probe)));
      probe[a][i] = x;
      grad[a][i] = (plus - minus) / (double(up) - double(down));  // the step float really took
    }
  }
  return grad;
}

}  // namespace

std::vector<Row> run_checks(gpu::Context& context, const DifferentiableKernel& kernel, const Tolerances& tol,
                            unsigned seed) {
  std::vector<Row> rows;
  const auto in_names = kernel.input_names();
  const auto out_names = kernel.output_names();
  for (const Case& c : kernel.cases()) {
    if (c.inputs.size() != in_names.size() || c.step_double.size() != in_names.size() ||
        c.step_float.size() != in_names.size())
      throw InternalError(kernel.name() + " case '" + c.name + "': inputs and steps must match the input names");
    const Arrays<float> in_f = cast<float>(c.inputs);
    const Arrays<double> in_d = cast<double>(in_f);  // both precisions see the same (float) point

    // Fixed random output weights: grad_out of L = sum w * out.
    const Arrays<double> ref_d = kernel.reference_forward(c.params, in_d);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> dist(-1.0, 1.0);
    Arrays<double> weights(ref_d.size());
    for (std::size_t a = 0; a < ref_d.size(); ++a) {
      weights[a].resize(ref_d[a].size());
      for (auto& w : weights[a]) w = double(float(dist(rng)));
    }
    const Arrays<float> weights_f = cast<float>(weights);

    Row base;
    base.kernel = kernel.name();
    base.case_name = c.name;

    base.check = "1 fwd gpu~ref";
    const Arrays<float> gpu_out = kernel.device_forward(context, c.params, in_f);
    compare(rows, base, out_names, gpu_out, kernel.reference_forward(c.params, in_f), tol.forward);

    base.check = "2 adj gpu~ref";
    const Arrays<float> gpu_grad = kernel.device_backward(context, c.params, in_f, weights_f);
    compare(rows, base, in_names, gpu_grad, kernel.reference_backward(c.params, in_f, weights_f), tol.adjoint);

    base.check = "3 adj ref~fd64";
    const Arrays<double> ref_grad = kernel.reference_backward(c.params, in_d, weights);
    const Arrays<double> fd_d = finite_differences<double>(
        in_d, c.step_double, weights, [&](const Arrays<double>& x) { return kernel.reference_forward(c.params, x); });
    compare_probed(rows, base, in_names, c.step_double, c.skip_reason, ref_grad, fd_d, tol.reference_fd);

    base.check = "4 adj gpu~fd32";
    const Arrays<double> fd_f = finite_differences<float>(
        in_f, c.step_float, weights, [&](const Arrays<float>& x) { return kernel.device_forward(context, c.params, x); });
    compare_probed(rows, base, in_names, c.step_float, c.skip_reason, gpu_grad, fd_f, tol.device_fd);
  }
  return rows;
}

bool all_passed(const std::vector<Row>& rows) {
  return std::all_of(rows.begin(), rows.end(), [](const Row& r) { return r.pass || r.skipped; });
}

void print_table(std::ostream& out, const std::vector<Row>& rows) {
  char line[512];
  std::snprintf(line, sizeof line, "%-24s %-16s %-15s %-12s %11s %11s %9s %s\n", "kernel", "case", "check", "array",
                "max abs", "max rel", "tol", "result");
  out << line;
  for (const Row& r : rows) {
    const char* verdict = r.skipped ? "skip" : !r.finite ? "FAIL (non-finite)" : r.pass ? "pass" : "FAIL";
    if (r.skipped) {
      std::snprintf(line, sizeof line, "%-24s %-16s %-15s %-12s %11s %11s %9s %s: %s\n", r.kernel.c_str(),
                    r.case_name.c_str(), r.check.c_str(), r.array.c_str(), "-", "-", "-", verdict, r.note.c_str());
    } else {
      std::snprintf(line, sizeof line, "%-24s %-16s %-15s %-12s %11.3e %11.3e %9.1e %s%s%s\n", r.kernel.c_str(),
                    r.case_name.c_str(), r.check.c_str(), r.array.c_str(), r.max_abs, r.max_rel, r.tolerance, verdict,
                    r.note.empty() ? "" : ": ", r.note.c_str());
    }
    out << line;
  }
}

json to_json(const std::vector<Row>& rows) {
  json out = json::array();
  for (const Row& r : rows)
    out.push_back({{"kernel", r.kernel}, {"case", r.case_name}, {"check", r.check}, {"array", r.array},
                   {"max_abs", r.max_abs}, {"max_rel", r.max_rel}, {"tolerance", r.tolerance}, {"finite", r.finite},
                   {"skipped", r.skipped}, {"pass", r.pass}, {"note", r.note}});
  return out;
}

}  // namespace nf::gradcheck
