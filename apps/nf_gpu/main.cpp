#include <iostream>
#include "engine/gpu/context.hpp"
int main() {
  nf::gpu::Context ctx;
  std::cout << nf::gpu::to_json(ctx.info()).dump(2) << "\n";
}
