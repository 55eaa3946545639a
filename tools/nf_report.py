#!/usr/bin/python3
"""Turns `nf_gpu bench` records (JSON arrays or JSON lines, any suites) into a one-page summary
(Markdown) and plots (PNG, Debian's python3-matplotlib): error against time for every record that
carries a curve, and the median time of every case.

usage: tools/nf_report.py RECORDS.json [MORE.json ...] --out DIR
"""
import argparse
import json
import os
import sys


def load(path):
    with open(path) as f:
        text = f.read().strip()
    if not text:
        return []
    if text[0] == "[":
        return json.loads(text)
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def headline(metrics):
    """The few numbers a reader wants first, whatever the suite."""
    keys = [k for k in metrics if isinstance(metrics[k], (int, float)) and not isinstance(metrics[k], bool)]
    return ", ".join(f"{k} {metrics[k]:.4g}" for k in keys[:4])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("records", nargs="+")
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    records = [r for path in args.records for r in load(path)]
    if not records:
        sys.exit("nf_report: no records in " + ", ".join(args.records))
    os.makedirs(args.out, exist_ok=True)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lines = ["# nf_gpu bench report", ""]
    devices = sorted({r.get("device", "?") for r in records})
    lines += [f"Device: {', '.join(devices)}. Records: {len(records)}.", ""]
    lines += ["| suite | case | median s | peak device MiB | headline metrics |", "|---|---|---|---|---|"]
    for r in records:
        mib = r.get("peak_device_bytes", 0) / 2**20
        lines.append(f"| {r['suite']} | {r['case']} | {r['seconds']['median']:.4g} | {mib:.0f} | "
                     f"{headline(r.get('metrics', {}))} |")

    curves = [r for r in records if "curve" in r and r["curve"].get("points")]
    if curves:
        fig, ax = plt.subplots(figsize=(7, 4))
        for r in curves:
            xs, ys = zip(*r["curve"]["points"])
            ax.plot(xs, ys, marker="o", label=f"{r['suite']}/{r['case']}")
        ax.set_xlabel(curves[0]["curve"].get("x", "seconds"))
        ax.set_ylabel(curves[0]["curve"].get("y", "error"))
        ax.set_yscale("log")
        ax.set_title("error against time")
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(os.path.join(args.out, "error_vs_time.png"), dpi=110)
        plt.close(fig)
        lines += ["", "![error against time](error_vs_time.png)"]

    fig, ax = plt.subplots(figsize=(7, 0.35 * len(records) + 1.2))
    labels = [f"{r['suite']}/{r['case']}" for r in records]
    ax.barh(labels, [r["seconds"]["median"] for r in records])
    ax.set_xscale("log")
    ax.set_xlabel("median wall seconds")
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "times.png"), dpi=110)
    plt.close(fig)
    lines += ["", "![median times](times.png)", ""]

    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write("\n".join(lines))
    print(os.path.join(args.out, "report.md"))


if __name__ == "__main__":
    main()
