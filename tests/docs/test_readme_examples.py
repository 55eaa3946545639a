#!/usr/bin/env python3
"""The README's runnable examples, run as written, in order, so they cannot drift from the binary.

Every `nf_gpu ...` line of the README's code blocks that holds no placeholder (WORK, DIR, [...],
a|b) is run in a scratch folder where `build/demo-scene` and `my_cat` are a tiny synthetic cat, and
`animals.json` is the README's batch manifest over copies of it.
Commands that run stages get small settings appended (those the line does not set itself, and
the step counts), so the README's own flags, setting names, joint and region names are what is
checked, not its minutes of work. A line's
trailing comment that says what reruns ("reruns fur and export only") is checked too.

usage: test_readme_examples.py NF_GPU README.md
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

# Small settings for commands that run stages: a setting the README's line names itself keeps the
# README's value (it is what the line is about), except the step counts, which only cost time.
TINY = ("neus.rays=128 neus.samples_per_ray=16 neus.fine_samples=8 neus.hull_fit_steps=5 neus.mesh_resolution=48"
        " neus.hull_resolution=48 body.samples=2000 body.hypothesis_steps=8 body.global_steps=10 body.pose_steps=20"
        " body.offset_steps=10 body.preview_views=1 defur.resolution=64 defur.preview_views=1 frames.roots=3000"
        " fur.warm_steps=4 fur.batch=400 fur.strands=20000 fur.metric_strands=300 fur.resolution=64 fur.preview_views=1"
        " fur.chamfer_queries=500 export.turntable_frames=2 export.compare_views=1").split()
STEPS = ["neus.steps=12", "fur.steps=12"]
# A strand count the README's line names is kept as a change (the line is about rerunning with
# more strands) but capped: 500,000 strands' inference and export only cost time here. It must
# differ from TINY's fur.strands, or the line would change nothing and rerun no stage.
MAX_STRANDS = 40000
STAGE_COMMANDS = ("reconstruct", "annotate")
PLACEHOLDER = re.compile(r"\[|\]|\||\.\.\.|\b(WORK|DIR|FILE|MESH|STAGE|SCENE|CM|EDIT_DIR|F)\b")


def examples(readme):
    """(line number, command, trailing comment) of the runnable nf_gpu lines in code blocks."""
    out, in_block, pending, start = [], False, "", 0
    with open(readme, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if line.startswith("```"):
                in_block, pending = not in_block, ""
                continue
            if not in_block:
                continue
            text = line.rstrip("\n")
            if pending:
                pending += " " + text.strip()
            elif text.startswith("nf_gpu "):
                pending, start = text, number
            else:
                continue
            if pending.endswith("\\"):
                pending = pending[:-1].rstrip()
                continue
            command, _, comment = pending.partition("#")
            pending = ""
            if not PLACEHOLDER.search(command):
                out.append((start, command.strip(), comment.strip()))
    return out


def batch_manifest(readme, scratch, scene):
    """The README's batch manifest (its JSON block with "scenes"), written to animals.json with the
    small settings merged into its defaults, and each scene it names made a copy of `scene`."""
    with open(readme, encoding="utf-8") as f:
        blocks = re.findall(r"```json\n(.*?)```", f.read(), re.S)
    manifests = [json.loads(b) for b in blocks if '"scenes"' in b]
    if not manifests:
        return
    manifest = manifests[0]
    settings = manifest.setdefault("defaults", {}).setdefault("settings", {})
    for setting in TINY + STEPS:
        key, value = setting.split("=")
        if key not in settings or key in ("neus.steps", "fur.steps"):
            settings[key] = value
    for entry in manifest["scenes"]:
        entry.get("settings", {}).pop("fur.steps", None)  # step counts only cost time
        shutil.copytree(scene, os.path.join(scratch, entry["scene"]))
    with open(os.path.join(scratch, "animals.json"), "w", encoding="utf-8") as f:
        json.dump(manifest, f)


def main():
    nf_gpu, readme = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    found = examples(readme)
    if len(found) < 4:
        print(f"FAIL: only {len(found)} runnable examples found in {readme}")
        return 1
    scratch = tempfile.mkdtemp(prefix="nf_readme_")
    failures = 0
    try:
        os.makedirs(os.path.join(scratch, "build"))
        synth = [nf_gpu, "synth", "--animal", "cat", "--views", "8", "--res", "64", "--strands", "4000", "--spp-axis", "1",
                 "--out", os.path.join(scratch, "build", "demo-scene")]
        subprocess.run(synth, check=True, capture_output=True)
        shutil.copytree(os.path.join(scratch, "build", "demo-scene"), os.path.join(scratch, "my_cat"))
        batch_manifest(readme, scratch, os.path.join(scratch, "build", "demo-scene"))
        for number, command, comment in found:
            args = command.split()[1:]
            capped = ""
            for i in range(len(args) - 1):
                key, _, value = args[i + 1].partition("=")
                if args[i] == "--set" and key == "fur.strands" and value.isdigit() and int(value) > MAX_STRANDS:
                    args[i + 1], capped = f"fur.strands={MAX_STRANDS}", f" (fur.strands capped at {MAX_STRANDS})"
            if args[0] in STAGE_COMMANDS:
                named = {args[i + 1].split("=")[0] for i in range(len(args) - 1) if args[i] == "--set"}
                for setting in [t for t in TINY if t.split("=")[0] not in named] + STEPS:
                    args += ["--set", setting]
            if args[0] == "reconstruct" and "--json" not in args:
                args.append("--json")
            started = time.monotonic()
            run = subprocess.run([nf_gpu] + args, cwd=scratch, capture_output=True, text=True)
            seconds = time.monotonic() - started
            ok = run.returncode == 0
            why = f"exit code {run.returncode}"
            match = re.search(r"reruns (.+) only", comment)
            if ok and match and args[0] == "reconstruct":
                stages = json.loads(run.stdout[run.stdout.index("["):])
                ran = {s["stage"] for s in stages if s["ran"]}
                said = set(re.split(r",\s*|\s+and\s+", match.group(1)))
                if ran != said:
                    ok, why = False, f"the comment says it reruns {sorted(said)}, it ran {sorted(ran)}"
            print(f"README.md:{number}: {'ok' if ok else 'FAIL'} ({seconds:.0f} s): {command}{capped}")
            if not ok:
                failures += 1
                print(f"  {why}\n" + "\n".join("  | " + l for l in (run.stdout + run.stderr).splitlines()[-15:]))
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    print(f"{len(found) - failures} of {len(found)} README examples ran as written")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
