#!/usr/bin/env python3
"""Compares the evaluations recorded in two strand-prior weights files (nf_gpu train-prior):
prints each set's fitted mean point error side by side and fails when they differ by more than
0.2 percentage points (float sums may differ between devices; on the same device they match)."""
import json
import struct
import sys


def record(path):
    with open(path, "rb") as f:
        head = f.read(12)
        if head[:4] != b"NFWT":
            sys.exit(f"{path}: not an nf_gpu weights file")
        (length,) = struct.unpack("<I", head[8:12])
        return json.loads(f.read(length))["config"]["record"]


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: compare_priors.py SHIPPED.nfwt REBUILT.nfwt")
    a, b = (record(p)["evaluation"]["sets"] for p in sys.argv[1:])
    worst = 0.0
    print(f"{'set':16} {'shipped':>10} {'rebuilt':>10}   (fitted mean point error, % of length)")
    for name in sorted(a):
        x, y = 100 * a[name]["fitted"]["mean"], 100 * b[name]["fitted"]["mean"]
        worst = max(worst, abs(x - y))
        print(f"{name:16} {x:10.3f} {y:10.3f}")
    print(f"largest difference: {worst:.3f} percentage points")
    sys.exit(0 if worst <= 0.2 else 1)


if __name__ == "__main__":
    main()
