// Every differentiable kernel of the catalog passes the four checks of the gradcheck protocol (engine/gradcheck/harness.hpp) on all its cases,
// and the harness itself catches a wrong adjoint, a wrong forward and a NaN.
#include <doctest/doctest.h>

#include <sstream>

#include "engine/gradcheck/catalog.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::gradcheck;

namespace {

// Wraps a real kernel and corrupts one part of it, to prove the harness notices.
class Corrupted : public DifferentiableKernel {
 public:
  enum class Fault { AdjointScale, AdjointSign, ForwardOffset, AdjointNaN };
  Corrupted(std::unique_ptr<DifferentiableKernel> inner, Fault fault) : inner_(std::move(inner)), fault_(fault) {}
  std::string name() const override { return inner_->name() + "+fault"; }
  std::vector<std::string> input_names() const override { return inner_->input_names(); }
  std::vector<std::string> output_names() const override { return inner_->output_names(); }
  std::vector<Case> cases() const override { return {inner_->cases().front()}; }
  Arrays<double> reference_forward(const Params& p, const Arrays<double>& in) const override {
    return inner_->reference_forward(p, in);
  }
  Arrays<float> reference_forward(const Params& p, const Arrays<float>& in) const override {
    return inner_->reference_forward(p, in);
  }
  Arrays<double> reference_backward(const Params& p, const Arrays<double>& in, const Arrays<double>& g) const override {
    return inner_->reference_backward(p, in, g);
  }
  Arrays<float> reference_backward(const Params& p, const Arrays<float>& in, const Arrays<float>& g) const override {
    return inner_->reference_backward(p, in, g);
  }
  Arrays<float> device_forward(gpu::Context& c, const Params& p, const Arrays<float>& in) const override {
    auto out = inner_->device_forward(c, p, in);
    if (fault_ == Fault::ForwardOffset) out[0][0] += 1e-3f;
    return out;
  }
  Arrays<float> device_backward(gpu::Context& c, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& g) const override {
    auto grad = inner_->device_backward(c, p, in, g);
    if (fault_ == Fault::AdjointScale) grad[0][4] *= 1.05f;
    if (fault_ == Fault::AdjointSign) grad[0][1] = -grad[0][1];
    if (fault_ == Fault::AdjointNaN) grad[0][2] = NAN;
    return grad;
  }

 private:
  std::unique_ptr<DifferentiableKernel> inner_;
  Fault fault_;
};

}  // namespace

TEST_CASE("every differentiable kernel passes the gradient-check protocol") {
  auto& ctx = test::context();
  const auto kernels = all_kernels();
  REQUIRE(!kernels.empty());
  for (const auto& kernel : kernels) {
    CAPTURE(kernel->name());
    const auto rows = run_checks(ctx, *kernel);
    std::ostringstream table;
    print_table(table, rows);
    INFO(table.str());
    CHECK(all_passed(rows));
    // All four checks reported on every case; a skip must say why, and only the difference checks may skip.
    for (const char* check : {"1 fwd gpu~ref", "2 adj gpu~ref", "3 adj ref~fd64", "4 adj gpu~fd32"})
      CHECK(std::count_if(rows.begin(), rows.end(), [&](const Row& r) { return r.check == check; }) >=
            long(kernel->cases().size()));
    for (const Row& r : rows)
      if (r.skipped) {
        CHECK((r.check == "3 adj ref~fd64" || r.check == "4 adj gpu~fd32"));
        CHECK(!r.note.empty());
      }
  }
}

TEST_CASE("the harness catches a wrong adjoint, a wrong forward and a NaN") {
  auto& ctx = test::context();
  for (auto fault : {Corrupted::Fault::AdjointScale, Corrupted::Fault::AdjointSign, Corrupted::Fault::ForwardOffset,
                     Corrupted::Fault::AdjointNaN}) {
    CAPTURE(int(fault));
    auto kernels = all_kernels();
    auto it = std::find_if(kernels.begin(), kernels.end(),
                           [](const auto& k) { return k->name() == "splat/segment_gaussian"; });  // cheap to probe
    REQUIRE(it != kernels.end());
    Corrupted broken(std::move(*it), fault);
    const auto rows = run_checks(ctx, broken);
    CHECK_FALSE(all_passed(rows));
    if (fault == Corrupted::Fault::AdjointNaN)
      CHECK(std::any_of(rows.begin(), rows.end(), [](const Row& r) { return !r.finite; }));
  }
}
