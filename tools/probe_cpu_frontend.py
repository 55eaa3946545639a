#!/usr/bin/env python3
"""Does the size of an unrolled kernel body limit lavapipe's multiply-add rate on this CPU?

Measures the instruction pattern that lavapipe (Mesa 22.3, LLVM 15, AVX-512VL) emits for the MLP
layer kernel (shaders/nn/mlp_fwd.comp): per input vec4 and output row, four multiplies by a
weight broadcast from memory (`vmulps mem{1to8}`), four adds, the accumulator kept on the stack.
llvmpipe lowers every fused multiply-add to a multiply and an add (lower_ffma32 in lp_screen.c),
so this is also what the core bench's FMA loop runs. The same pattern is timed as one body of
64 input vec4 x 32 rows (a 256-input layer's products) and as bodies of 32, 24 and 16 input vec4,
each in a loop, on one core. Not part of the build; needs a C compiler and binutils.

usage: tools/probe_cpu_frontend.py [--seconds S]
"""
import argparse
import os
import subprocess
import sys
import tempfile

ROWS = 32
SIZES = [64, 32, 24, 16]  # input vec4 per body


def body(name, in4):
    lines = [f".globl {name}", f"{name}:", "  push %rbp", "  mov %rsp,%rbp", "  sub $2048,%rsp", "  and $-64,%rsp",
             "  vxorps %ymm20,%ymm20,%ymm20", "  vxorps %ymm0,%ymm0,%ymm0", "  vxorps %ymm1,%ymm1,%ymm1",
             "  vxorps %ymm2,%ymm2,%ymm2", "  vxorps %ymm3,%ymm3,%ymm3"]
    lines += [f"  vmovaps %ymm20,{c * 32}(%rsp)" for c in range(ROWS)]
    lines.append("1:")
    for k4 in range(in4):
        for c in range(ROWS):
            w = (c * 64 + k4) * 16  # weights row-major, as the kernel stages them in shared memory
            lines += [f"  vmulps {w + 12}(%rsi){{1to8}},%ymm3,%ymm4", f"  vaddps {c * 32}(%rsp),%ymm4,%ymm4",
                      f"  vmulps {w + 8}(%rsi){{1to8}},%ymm2,%ymm5", "  vaddps %ymm4,%ymm5,%ymm4",
                      f"  vmulps {w + 4}(%rsi){{1to8}},%ymm1,%ymm5", "  vaddps %ymm4,%ymm5,%ymm4",
                      f"  vmulps {w}(%rsi){{1to8}},%ymm0,%ymm5", "  vaddps %ymm4,%ymm5,%ymm4",
                      f"  vmovaps %ymm4,{c * 32}(%rsp)"]
    lines += ["  dec %rdi", "  jnz 1b", "  mov %rbp,%rsp", "  pop %rbp", "  vzeroupper", "  ret", f".size {name}, .-{name}"]
    return "\n".join(lines)


DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
%(decls)s
static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + t.tv_nsec * 1e-9; }
int main(int argc, char** argv) {
  double seconds = atof(argv[1]);
  float* w = aligned_alloc(64, 1 << 20);
  for (int i = 0; i < (1 << 18); ++i) w[i] = 0.0f;
  void (*bodies[])(long, float*) = {%(names)s};
  int sizes[] = {%(sizes)s};
  for (int b = 0; b < %(count)d; ++b) {
    long per_call = (long)sizes[b] * 4 * %(rows)d, n = 1000;
    double t0 = now(), dt;
    bodies[b](n, w);
    dt = now() - t0;
    n = (long)(n * seconds / (dt > 1e-6 ? dt : 1e-6)) + 1;
    t0 = now();
    bodies[b](n, w);
    dt = now() - t0;
    printf("%%d %%.3f\n", sizes[b], n * (double)per_call / dt / 1e9);
  }
  return 0;
}
"""


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=1.0, help="time per body")
    args = parser.parse_args()
    if "avx512vl" not in open("/proc/cpuinfo").read():
        print("probe_cpu_frontend: this CPU has no AVX-512VL, so lavapipe emits other code here; nothing to measure")
        return 2
    names = [f"body_{n}" for n in SIZES]
    with tempfile.TemporaryDirectory() as tmp:
        with open(os.path.join(tmp, "bodies.S"), "w") as f:
            f.write(".text\n" + "\n".join(body(n, s) for n, s in zip(names, SIZES)) +
                    "\n.section .note.GNU-stack,\"\",@progbits\n")
        with open(os.path.join(tmp, "driver.c"), "w") as f:
            f.write(DRIVER % {"decls": "\n".join(f"void {n}(long, float*);" for n in names),
                              "names": ", ".join(names), "sizes": ", ".join(map(str, SIZES)),
                              "count": len(SIZES), "rows": ROWS})
        exe = os.path.join(tmp, "probe")
        subprocess.run(["cc", "-O2", "-o", exe, os.path.join(tmp, "driver.c"), os.path.join(tmp, "bodies.S")],
                       check=True)
        out = subprocess.run([exe, str(args.seconds)], check=True, capture_output=True, text=True).stdout
        symbols = subprocess.run(["nm", "-S", exe], check=True, capture_output=True, text=True).stdout
    code_bytes = {}
    for row in symbols.splitlines():
        fields = row.split()
        if len(fields) == 4 and fields[3].startswith("body_"):
            code_bytes[int(fields[3][5:])] = int(fields[1], 16)
    rates = {}
    for row in out.strip().splitlines():
        in4, rate = row.split()
        rates[int(in4)] = float(rate)
        print(f"body of {int(in4):2d} input vec4 x {ROWS} rows ({code_bytes[int(in4)] / 1024:.0f} KB of code): "
              f"{float(rate):.2f} G vector multiply-adds/s on one core ({float(rate) * 16:.0f} GFLOP/s)")
    print(f"the {SIZES[0]}-vec4 body runs at {rates[SIZES[0]] / rates[SIZES[-1]]:.2f}x the rate of the "
          f"{SIZES[-1]}-vec4 one")
    return 0


if __name__ == "__main__":
    sys.exit(main())
