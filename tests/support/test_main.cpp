// doctest main shared by every suite: runs the tests, then fails the process if the Khronos
// validation layer reported anything during the run (the messages are printed as they come).
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdio>
#include <memory>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define NF_TEST_ASAN 1
#endif
#endif
#if NF_TEST_ASAN
#include <dlfcn.h>
#include <link.h>
#endif

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

#if NF_TEST_ASAN
// Under LeakSanitizer only: marks every shared object loaded now (the Vulkan drivers among them) as
// never to be unloaded. The loader dlcloses its drivers at vkDestroyInstance; a driver's once-only
// state (lavapipe in Mesa 22.3.6-1+deb12u2 keeps 128 bytes from a pthread_once initialiser in a
// static) then loses its last pointer and reads as a leak from an unknown module. Kept loaded, that
// state stays reachable, while a real leak is still reported, with a stack that can be symbolised.
void keep_loaded_libraries() {
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void*) -> int {
        if (info->dlpi_name != nullptr && info->dlpi_name[0] != '\0') {
          if (void* handle = dlopen(info->dlpi_name, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE)) dlclose(handle);
        }
        return 0;
      },
      nullptr);
}
#else
void keep_loaded_libraries() {}
#endif

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
    nf::test::keep_loaded_libraries();
    nf::test::holder().reset();
  }
  return result;
}
