#pragma once
// The gradient-check protocol (README, gradcheck), for any differentiable kernel:
//   1. GPU forward  == CPU reference forward (float)
//   2. GPU adjoint  == CPU reference adjoint (float)
//   3. CPU reference adjoint (double) == central finite differences of the reference (double)
//   4. GPU adjoint  == central finite differences of the GPU forward (float, where float resolves the step)
// The scalar probed is L = sum_k w_k * out_k with fixed random weights w, so the adjoint under test
// is fed grad_out = w. Errors are reported per input (or output) array: max absolute error and the
// max error relative to the array's largest reference magnitude (an infinity-norm relative error,
// which stays meaningful where single elements are near zero). Every row also checks that all
// values are finite: a tolerance test alone passes on NaN.
#include <functional>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "engine/core/json.hpp"

namespace nf::gpu {
class Context;
}

namespace nf::gradcheck {

template <class T>
using Arrays = std::vector<std::vector<T>>;
using Params = std::map<std::string, double>;

struct Case {
  std::string name;
  Params params;                     // non-differentiable settings of the kernel
  Arrays<double> inputs;
  std::vector<double> step_double;   // central-difference step per input array (check 3); 0 skips it
  std::vector<double> step_float;    // per input array for check 4; 0 skips it
  std::string skip_reason;           // why a check is skipped (a kink, float resolution...), when one is
};

class DifferentiableKernel {
 public:
  virtual ~DifferentiableKernel() = default;
  virtual std::string name() const = 0;
  virtual std::vector<std::string> input_names() const = 0;
  virtual std::vector<std::string> output_names() const = 0;
  virtual std::vector<Case> cases() const = 0;

  virtual Arrays<double> reference_forward(const Params&, const Arrays<double>& in) const = 0;
  virtual Arrays<float> reference_forward(const Params&, const Arrays<float>& in) const = 0;
  virtual Arrays<double> reference_backward(const Params&, const Arrays<double>& in,
                                            const Arrays<double>& grad_out) const = 0;
  virtual Arrays<float> reference_backward(const Params&, const Arrays<float>& in,
                                           const Arrays<float>& grad_out) const = 0;
  virtual Arrays<float> device_forward(gpu::Context&, const Params&, const Arrays<float>& in) const = 0;
  virtual Arrays<float> device_backward(gpu::Context&, const Params&, const Arrays<float>& in,
                                        const Arrays<float>& grad_out) const = 0;
};

// Implements the four reference overrides from one templated pair in Derived:
//   template <class T> Arrays<T> forward(const Params&, const Arrays<T>&) const;
//   template <class T> Arrays<T> backward(const Params&, const Arrays<T>&, const Arrays<T>&) const;
template <class Derived>
class WithReference : public DifferentiableKernel {
 public:
  Arrays<double> reference_forward(const Params& p, const Arrays<double>& in) const override {
    return self().template forward<double>(p, in);
  }
  Arrays<float> reference_forward(const Params& p, const Arrays<float>& in) const override {
    return self().template forward<float>(p, in);
  }
  Arrays<double> reference_backward(const Params& p, const Arrays<double>& in, const Arrays<double>& g) const override {
    return self().template backward<double>(p, in, g);
  }
  Arrays<float> reference_backward(const Params& p, const Arrays<float>& in, const Arrays<float>& g) const override {
    return self().template backward<float>(p, in, g);
  }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
};

struct Tolerances {
  double forward = 1e-5;       // check 1, relative
  double adjoint = 1e-4;       // check 2, relative
  double reference_fd = 1e-6;  // check 3, relative
  double device_fd = 1e-2;     // check 4, relative
};

struct Row {
  std::string kernel, case_name, check, array;
  double max_abs = 0, max_rel = 0, tolerance = 0;
  bool finite = true, skipped = false, pass = true;
  std::string note;
};

std::vector<Row> run_checks(gpu::Context& context, const DifferentiableKernel& kernel,
                            const Tolerances& tolerances = {}, unsigned seed = 1);

void print_table(std::ostream& out, const std::vector<Row>& rows);
json to_json(const std::vector<Row>& rows);
bool all_passed(const std::vector<Row>& rows);

}  // namespace nf::gradcheck
