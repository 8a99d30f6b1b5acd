#!/usr/bin/python3
"""The picture in wind, for trying levers (any canopy-demo option through --extra); the measure of
record is `canopy-bench picture` (bench/bench_picture.cpp: the same frames, in memory, and the table
of docs/performance.md "The picture in wind"). Each frame with wind
against the same frame (camera, time) without it (--wind-speed 0), for the 2D method and the
per-vertex baseline, measured by canopy-demo --measure-foliage (tools/foliage_measure.h):

  coverage   foliage pixels with wind / without
  sharpness  mean luminance gradient over the foliage pixels, with wind / without (below 1: blurred)

Runs: every scene x path x size x method x wind. Scenes: field, shrub (generated), tree:PATH (a real
glTF plant), file:PATH (a scene file, e.g. demo/scenes/six_species.json). Paths: still, walk
(first person, close up), orbit (9 degrees a frame). Winds: breeze (the library's default
WorldWind.speed) and gale (3x it).

Usage: scripts/picture.py DEMO OUT_DIR [--scenes field,shrub,tree:P,file:P] [--paths still,walk,orbit]
       [--sizes 640x480,1280x720] [--methods 2d,per-vertex] [--winds breeze,gale] [--frames N]
       [--extra="--sharpness 3"] [--check] [--json FILE] [--table FILE]
  --check  exit 1 unless issue 67's bounds hold for every 2D run: breeze median sharpness >= 0.85,
           min >= 0.75, coverage >= 0.9 on every frame; gale median sharpness >= 0.7, coverage
           >= 0.85 on every frame
  --table  write the runs as a markdown table (docs/performance.md's)
Frames whose still twin has no foliage pixels are left out; a run with none is reported as not
measured (a first-person walk under a single tree sees its trunk). Plain Python, no numpy."""
import argparse
import json
import os
import subprocess
import sys

BREEZE_MPS = 3.0  # WorldWind.speed's default (render/include/canopy/canopy_params.h)
GALE_FACTOR = 3.0
# Issue 67's bounds: (median sharpness, least sharpness, least coverage) per wind.
BOUNDS = {"breeze": (0.85, 0.75, 0.90), "gale": (0.70, 0.0, 0.85)}


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"picture: {' '.join(cmd)} exited {r.returncode}:\n{r.stdout[-2000:]}{r.stderr[-2000:]}")
    return r.stdout


def measure(demo, wind_dir, still_dir):
    lines = run([demo, "--measure-foliage", wind_dir, still_dir]).splitlines()
    names = lines[1].split()
    rows = []
    for line in lines[2:]:
        parts = line.split()
        if len(parts) == len(names) and parts[0].isdigit():
            rows.append({n: float(v) for n, v in zip(names, parts)})
    return rows


def median(v):
    s = sorted(v)
    n = len(s)
    return float("nan") if n == 0 else (s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2]))


def scene_args(scene):
    if scene.startswith("tree:"):
        return ["--gltf", scene[5:]], os.path.splitext(os.path.basename(scene[5:]))[0]
    if scene.startswith("file:"):
        return ["--scene-file", scene[5:]], os.path.splitext(os.path.basename(scene[5:]))[0]
    return ["--scene", scene], scene


def path_args(path, frames):
    if path == "still":
        return []
    if path == "orbit":
        return ["--camera", "orbit", "--degrees-per-frame", "9"]
    if path == "walk":
        return ["--camera", "walk"]
    sys.exit(f"picture: unknown path {path} (still, walk, orbit)")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("demo")
    ap.add_argument("out")
    ap.add_argument("--scenes", default="field,shrub")
    ap.add_argument("--paths", default="still,walk,orbit")
    ap.add_argument("--sizes", default="640x480")
    ap.add_argument("--methods", default="2d,per-vertex")
    ap.add_argument("--winds", default="breeze")
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument("--extra", default="")
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--json", default="")
    ap.add_argument("--table", default="")
    o = ap.parse_args()
    extra = o.extra.split() if o.extra else []
    results, failures = [], []
    for scene in o.scenes.split(","):
        sargs, name = scene_args(scene)
        for path in o.paths.split(","):
            for size in o.sizes.split(","):
                for wind in o.winds.split(","):
                    speed = BREEZE_MPS * (GALE_FACTOR if wind == "gale" else 1.0)
                    row = {"scene": name, "path": path, "size": size, "wind": wind, "speed_mps": speed}
                    for method in o.methods.split(","):
                        tag = os.path.join(o.out, f"{name}_{path}_{size}_{wind}_{method}")
                        common = sargs + path_args(path, o.frames) + ["--method", method, "--size", size, "--frames",
                                                                       str(o.frames), "--no-mp4"] + extra
                        run([o.demo, "--out", tag + "_wind", "--wind-speed", str(speed)] + common)
                        run([o.demo, "--out", tag + "_still", "--wind-speed", "0"] + common)
                        m = [r for r in measure(o.demo, tag + "_wind", tag + "_still") if r["still_px"] > 0]
                        if not m:  # e.g. a first-person walk under one tree sees its trunk alone
                            row["2d" if method == "2d" else "pv"] = None
                            print(f"picture: {name} {path} {size} {wind} {method}: no foliage in view, not measured")
                            continue
                        sharp = [r["sharpness"] for r in m]
                        cover = [r["coverage"] for r in m]
                        key = "2d" if method == "2d" else "pv"
                        row[key] = {"sharpness_median": median(sharp), "sharpness_min": min(sharp),
                                    "coverage_min": min(cover), "coverage_median": median(cover),
                                    "sharpness": sharp, "coverage": cover}
                        if method == "2d":
                            med, least, cov = BOUNDS[wind]
                            r = row[key]
                            if r["sharpness_median"] < med or r["sharpness_min"] < least or r["coverage_min"] < cov:
                                failures.append(f"{name} {path} {size} {wind}: sharpness median {r['sharpness_median']:.3f} "
                                                f"(>= {med}) min {r['sharpness_min']:.3f} (>= {least}), coverage min "
                                                f"{r['coverage_min']:.3f} (>= {cov})")
                    if not row.get("2d") and not row.get("pv"):
                        continue
                    results.append(row)
                    short = {k: ({kk: round(vv, 3) for kk, vv in v.items() if not isinstance(vv, list)} if isinstance(v, dict) else v)
                             for k, v in row.items()}
                    print(json.dumps(short), flush=True)
    if o.json:
        with open(o.json, "w") as fh:
            json.dump(results, fh, indent=1)
    if o.table:
        with open(o.table, "w") as fh:
            fh.write("| scene | path | size | wind | 2D sharpness median / min | 2D coverage min | per-vertex sharpness median / min | per-vertex coverage min |\n")
            fh.write("|---|---|---|---|---|---|---|---|\n")
            for r in results:
                cells = []
                for key in ("2d", "pv"):
                    m = r.get(key)
                    cells += [f"{m['sharpness_median']:.2f} / {m['sharpness_min']:.2f}", f"{m['coverage_min']:.2f}"] if m else ["-", "-"]
                fh.write(f"| {r['scene']} | {r['path']} | {r['size']} | {r['wind']} ({r['speed_mps']:g} m/s) | " + " | ".join(cells) + " |\n")
    if o.check:
        for f in failures:
            print(f"picture: {f}")
        print(f"picture: {'FAILED' if failures else 'all within'} issue 67's bounds ({len(results)} runs)")
        sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
