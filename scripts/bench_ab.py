#!/usr/bin/env python3
"""Two builds' `canopy-bench table1` alternated in one run (A B B A A B ..., so a drift of the
machine falls on both alike), and each row's median frame time compared.

  python3 scripts/bench_ab.py OLD_BENCH NEW_BENCH [--pairs N] [--rows still] [-- table1 options]

Prints, per row (faces, layout, camera), the median over the runs of each build's row median, the
ratio new/old and how many of the adjacent old/new pairs have the new build slower. Defaults:
4 pairs, the still rows, `table1 --faces 80000 --frames 30 --json ''`.
"""
import argparse
import re
import statistics
import subprocess
import sys

ROW = re.compile(r"^\s+(\d+)\s+(\S+)\s+(still|orbit)\s+([\d.]+)\s")


def run(bench, extra):
    out = subprocess.run([bench, "table1"] + extra, check=True, capture_output=True, text=True).stdout
    rows = {}
    for line in out.splitlines():
        m = ROW.match(line)
        if m:
            rows[(m.group(1), m.group(2), m.group(3))] = float(m.group(4))
    if not rows:
        sys.exit(f"bench_ab: no Table 1 rows in the output of {bench}")
    return rows


def main():
    argv = sys.argv[1:]
    extra = ["--faces", "80000", "--frames", "30", "--json", ""]
    if "--" in argv:
        i = argv.index("--")
        argv, extra = argv[:i], argv[i + 1:]
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--pairs", type=int, default=4)
    ap.add_argument("--rows", choices=["still", "orbit", "all"], default="still")
    a = ap.parse_args(argv)
    runs = {"old": [], "new": []}
    for p in range(a.pairs):
        order = ["old", "new"] if p % 2 == 0 else ["new", "old"]
        for which in order:
            rows = run(a.old if which == "old" else a.new, extra)
            runs[which].append(rows)
            shown = "  ".join(f"{k[1]} {k[2]} {v:.2f}" for k, v in rows.items() if a.rows in ("all", k[2]))
            print(f"pair {p + 1} {which}: {shown}", flush=True)
    print(f"\n{'row':<26} {'old ms':>8} {'new ms':>8} {'new/old':>8}  new slower in")
    for key in runs["old"][0]:
        if a.rows != "all" and key[2] != a.rows:
            continue
        old = [r[key] for r in runs["old"]]
        new = [r[key] for r in runs["new"]]
        mo, mn = statistics.median(old), statistics.median(new)
        slower = sum(n > o for o, n in zip(old, new))
        print(f"{' '.join(key):<26} {mo:8.2f} {mn:8.2f} {mn / mo:8.3f}  {slower} of {len(old)} pairs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
