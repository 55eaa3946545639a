#!/usr/bin/python3
"""PyTorch CPU peer for `nf_gpu bench --suite nn`: one MLP training step (forward, MSE, backward,
AdamW) timed the same way, printed as JSON. Needs Debian's python3-torch and libopenblas0-openmp
(`tools/nf bench` installs them); run with /usr/bin/python3. `--device cuda` times the same step
on a CUDA GPU instead (a PyTorch with CUDA), the peer for runs of the bench on an NVIDIA GPU."""
import argparse
import json
import statistics
import time

try:
    import torch
except ImportError as e:  # reported by nf_gpu as an unavailable peer
    print(json.dumps({"available": False, "why": f"python3-torch not importable: {e}"}))
    raise SystemExit(0)

parser = argparse.ArgumentParser()
parser.add_argument("--inputs", type=int, required=True)
parser.add_argument("--hidden", type=str, required=True)
parser.add_argument("--outputs", type=int, required=True)
parser.add_argument("--activation", default="relu")
parser.add_argument("--batch", type=int, required=True)
parser.add_argument("--steps", type=int, default=7)
parser.add_argument("--device", default="cpu")
args = parser.parse_args()

torch.manual_seed(0)
act = {"relu": torch.nn.ReLU, "softplus": lambda: torch.nn.Softplus(beta=100), "none": torch.nn.Identity}[args.activation]
widths = [args.inputs] + [int(h) for h in args.hidden.split(",")] + [args.outputs]
layers = []
for i in range(len(widths) - 1):
    layers.append(torch.nn.Linear(widths[i], widths[i + 1]))
    if i + 2 < len(widths):
        layers.append(act())
net = torch.nn.Sequential(*layers).to(args.device)
opt = torch.optim.AdamW(net.parameters(), lr=1e-3, weight_decay=0.0)
x = torch.rand(args.batch, args.inputs, device=args.device)
y = torch.rand(args.batch, args.outputs, device=args.device) - 0.5


def step():
    opt.zero_grad(set_to_none=True)
    loss = torch.nn.functional.mse_loss(net(x), y)
    loss.backward()
    opt.step()
    return loss.item()


step()  # warm-up
times = []
for _ in range(args.steps):
    t0 = time.perf_counter()
    step()
    times.append(time.perf_counter() - t0)
flops = 0
for i in range(len(widths) - 1):
    flops += 2 * widths[i] * widths[i + 1] * (3 if i > 0 else 2)
median = statistics.median(times)
print(json.dumps({
    "available": True,
    "torch": torch.__version__,
    "device": args.device,
    "threads": torch.get_num_threads(),
    "blas": "openblas" if "openblas" in torch.__config__.show().lower() else "other",
    "train_seconds_per_step": median,
    "train_samples_per_s": args.batch / median,
    "train_GFLOPs": args.batch * flops / median / 1e9,
}))
