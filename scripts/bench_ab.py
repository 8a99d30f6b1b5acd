#!/usr/bin/env python3
"""Two builds' `canopy-bench table1` (or `camera`) alternated in one run (A B B A A B ..., so a
drift of the machine falls on both alike), and each row's median frame time compared.

  python3 scripts/bench_ab.py OLD_BENCH NEW_BENCH [--pairs N] [--rows still] [-- table1 options]
  python3 scripts/bench_ab.py OLD_BENCH NEW_BENCH --section camera [--pairs N] [-- camera options]

Prints, per row (faces, layout, camera), the median over the runs of each build's row median, the
ratio new/old and how many of the adjacent old/new pairs have the new build slower. Defaults:
4 pairs, the still rows, `table1 --faces 80000 --frames 30 --json ''`. With `--section camera`
the rows are each face count's still camera and each path's frame under the policy ("auto ms"),
default `camera --faces 80000 --frames 20 --paths turn --budget 0`. With `--section layers` the
rows are each face count's foliage draws of a re-slice (GPU ms per draw path), default
`layers --faces 80000 --rebuilds 7`.
"""
import argparse
import re
import statistics
import subprocess
import sys

ROW = re.compile(r"^\s+(\d+)\s+(\S+)\s+(still|orbit)\s+([\d.]+)\s")
CAMERA_STILL = re.compile(r"^(\d+) faces: still camera ([\d.]+) ms")
CAMERA_PATH = re.compile(r"^\s+(orbit|dolly|strafe|turn|zoom|walk)\s+([\d.]+)\s")
LAYERS_FACES = re.compile(r"^\s+(\d+)\s+[\d.]+\s+[\d.]+\s+[\d.]+ \|")
LAYERS_DRAW = re.compile(r"\| (\d+ draws?, [^|]*?)\s+([\d.]+)\s+[\d.]+\s+[\d.]+\s+[\d.]+$")


def run(bench, section, extra):
    out = subprocess.run([bench, section] + extra, check=True, capture_output=True, text=True).stdout
    rows = {}
    faces = "?"
    for line in out.splitlines():
        if section == "layers":
            m = LAYERS_FACES.match(line)
            if m:
                faces = m.group(1)
            m = LAYERS_DRAW.search(line)
            if m:
                rows[(faces, "-", m.group(1).replace(" ", "_"))] = float(m.group(2))
            continue
        if section == "table1":
            m = ROW.match(line)
            if m:
                rows[(m.group(1), m.group(2), m.group(3))] = float(m.group(4))
            continue
        m = CAMERA_STILL.match(line)
        if m:
            faces = m.group(1)
            rows[(faces, "-", "still")] = float(m.group(2))
        m = CAMERA_PATH.match(line)
        if m:
            rows[(faces, "-", m.group(1))] = float(m.group(2))
    if not rows:
        sys.exit(f"bench_ab: no {section} rows in the output of {bench}")
    return rows


def main():
    argv = sys.argv[1:]
    extra = None
    if "--" in argv:
        i = argv.index("--")
        argv, extra = argv[:i], argv[i + 1:]
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--pairs", type=int, default=4)
    ap.add_argument("--rows", choices=["still", "orbit", "all"], default="still")
    ap.add_argument("--section", choices=["table1", "camera", "layers"], default="table1")
    a = ap.parse_args(argv)
    if a.section == "layers":
        a.rows = "all"
        if extra is None:
            extra = ["--faces", "80000", "--rebuilds", "7"]
    elif a.section == "camera":
        a.rows = "all"
        if extra is None:
            extra = ["--faces", "80000", "--frames", "20", "--paths", "turn", "--budget", "0"]
    elif extra is None:
        extra = ["--faces", "80000", "--frames", "30", "--json", ""]
    runs = {"old": [], "new": []}
    for p in range(a.pairs):
        order = ["old", "new"] if p % 2 == 0 else ["new", "old"]
        for which in order:
            rows = run(a.old if which == "old" else a.new, a.section, extra)
            runs[which].append(rows)
            shown = "  ".join(f"{k[1]} {k[2]} {v:.2f}" for k, v in rows.items() if a.rows in ("all", k[2]))
            print(f"pair {p + 1} {which}: {shown}", flush=True)
    width = max([26] + [len(" ".join(k)) for k in runs["old"][0]])
    print(f"\n{'row':<{width}} {'old ms':>8} {'new ms':>8} {'new/old':>8}  new slower in")
    for key in runs["old"][0]:
        if a.rows != "all" and key[2] != a.rows:
            continue
        old = [r[key] for r in runs["old"]]
        new = [r[key] for r in runs["new"]]
        mo, mn = statistics.median(old), statistics.median(new)
        slower = sum(n > o for o, n in zip(old, new))
        print(f"{' '.join(key):<{width}} {mo:8.2f} {mn:8.2f} {mn / mo:8.3f}  {slower} of {len(old)} pairs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
