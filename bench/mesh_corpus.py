"""Meshes every surface of a corpus with `kardia mesh`: see bench/mesh-corpus.sh."""

import json
import os
import re
import subprocess
import sys
import tempfile
import time

corpus, binary = sys.argv[1], sys.argv[2]
kind = os.environ.get("KIND", "").split()
limit = float(os.environ.get("LIMIT", "60"))
only = re.compile(os.environ.get("ONLY", ""))
log = open(os.environ["LOG"], "w") if os.environ.get("LOG") else None

surfaces = [
    s
    for s in json.load(open(corpus))["surfaces"]
    if s["degree"] <= 16 and only.search(s["id"])
]
buckets = [(1.0, "≤ 1"), (1.1, "1–1.1"), (1.5, "1.1–1.5"), (2.0, "1.5–2"), (float("inf"), "> 2")]
counts = {name: 0 for _, name in buckets}
counts["not measured"] = 0
away = {name: 0 for _, name in buckets}
meshed, refused, other, late, seconds = 0, [], [], [], []
with tempfile.TemporaryDirectory() as out:
    for s in surfaces:
        radius = float(s["radius"])
        args = list(kind)
        if args[:1] == ["--shell"]:
            args = ["--shell", str(float(args[1]) * radius)]
        command = [binary, "mesh", "--quiet", "--equation=" + s["kardia"],
                   "--bound", str(radius), *args, "-o", os.path.join(out, "mesh.stl")]
        started = time.monotonic()
        try:
            run = subprocess.run(command, capture_output=True, text=True, timeout=limit)
            status, text = run.returncode, run.stdout + run.stderr
        except subprocess.TimeoutExpired:
            status, text = "time limit", ""
        took = time.monotonic() - started
        if log:
            summary = text.replace("\n", " | ")
            log.write(f"{s['id']}\t{status}\t{took:.2f}\t{summary}\n")
        if status == "time limit":
            late.append(f"{s['id']}: past the time limit ({limit:g} s)")
            continue
        if status != 0:
            line = text.strip().splitlines()[-1]
            (refused if "failed its own check" in text else other).append(f"{s['id']}: {line}")
            continue
        meshed += 1
        seconds.append(took)
        found = re.search(r"Hausdorff estimate ([0-9.e+-]+)", text)
        if not found:  # a shell's polynomial above degree 16
            counts["not measured"] += 1
            continue
        ratio = float(found.group(1)) / (0.01 * radius)
        counts[next(name for top, name in buckets if ratio <= top)] += 1
        # Away from the parts thinner than the grid step (the summary's "elsewhere", when
        # some samples beyond the tolerance are there).
        elsewhere = re.search(r"elsewhere the largest distance is ([0-9.e+-]+)", text)
        if elsewhere:
            ratio = float(elsewhere.group(1)) / (0.01 * radius)
        away[next(name for top, name in buckets if ratio <= top)] += 1

for line in refused + other + late:
    print(line)
seconds.sort()
print(f"\n{len(surfaces)} surfaces{' ' + ' '.join(kind) if kind else ''}: {meshed} meshed, "
      f"{len(refused)} refused by the check, {len(other)} other answers, "
      f"{len(late)} past the time limit")
if seconds:
    print(f"seconds per run: median {seconds[len(seconds) // 2]:.2f}, largest {seconds[-1]:.2f}")
print("Hausdorff estimate / tolerance: " + ", ".join(f"{n} {c}" for n, c in counts.items()))
print("away from parts thinner than the grid step: " + ", ".join(f"{n} {c}" for n, c in away.items()))
