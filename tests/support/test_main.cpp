// doctest main shared by every suite: runs the tests, then fails the process if the Khronos
// validation layer reported anything during the run (the messages are printed as they come).
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdio>
#include <memory>

#include "engine/gpu/shader_registry.hpp"
#include "tests/support/gpu_test.hpp"

namespace nf::gpu::detail {
const ShaderTable& test_shader_table();  // tests/shaders, built by tests/CMakeLists.txt
}

namespace nf::test {
std::unique_ptr<gpu::Context>& holder() {
  static std::unique_ptr<gpu::Context> context;
  return context;
}

gpu::Context& context() {
  if (!holder()) holder() = std::make_unique<gpu::Context>();
  return *holder();
}
bool context_created() { return holder() != nullptr; }

}  // namespace nf::test

int main(int argc, char** argv) {
  nf::gpu::register_shaders(nf::gpu::detail::test_shader_table());
  doctest::Context runner(argc, argv);
  int result = runner.run();
  if (nf::test::context_created()) {
    const auto messages = nf::test::context().take_validation_messages();
    if (!messages.empty()) {
      std::fprintf(stderr, "FAILED: %zu Vulkan validation message(s) during the run (see above)\n", messages.size());
      result = 1;
    }
    nf::test::holder().reset();
  }
  return result;
}
