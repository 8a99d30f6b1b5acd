#!/usr/bin/python3
"""The wind seen from every side (issue 66): runs canopy-demo on a scene with the wind and without it
(--wind-speed 0 as the still reference: the same cameras and times) and measures each frame.

  coverage  foliage pixels with wind / without, the same frame (foliage: green above red and blue by
            15 levels, the issue's measure)
  offset    the crown's horizontal offset, pixels: the centroid x of the foliage pixels in the top
            third of the still frame's foliage rows, with wind minus without
  sway      the top third's centroid x range over the run (max - min) / the foliage's on-screen height

Cases (each for the 2D method and the per-vertex baseline):
  orbit     a 360-degree orbit at 9 degrees a frame, 40 frames: coverage on every frame
  yaw0/180  still cameras at --yaw 0 and --yaw 180, 60 frames: the offsets' correlation (mirrored: -1)
  yaw90     a still camera at --yaw 90: coverage
  breeze    the default shrub, still camera, 120 frames (4 s at 30 fps): the sway

Usage: scripts/wind_views.py DEMO OUT_DIR [--scenes shrub,field,gltf:PATH] [--size 320x240]
       [--methods 2d,per-vertex] [--cases orbit,mirror,yaw90,breeze] [--extra="--wind-speed 9"]
       [--quick] [--check] [--json FILE]
  --quick  fewer frames (orbit 12 at 30 degrees, mirror 30, yaw90 10, breeze 60): the ctest's run
  --check  exit 1 unless every orbit and yaw-90 frame keeps coverage >= 0.9 and the mirror
           correlation is <= -0.6 (issue 66's bounds)
The frames are measured by the demo itself (canopy-demo --measure-foliage, tools/foliage_measure.h):
plain Python, no numpy."""
import argparse
import json
import math
import os
import subprocess
import sys


def run_demo(demo, out, args):
    cmd = [demo, "--out", out, "--no-mp4"] + args
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"wind_views: {' '.join(cmd)} exited {r.returncode}:\n{r.stdout[-2000:]}{r.stderr[-2000:]}")
    return sorted(f for f in os.listdir(out) if f.startswith("frame_") and f.endswith(".png"))


def measure_folders(demo, wind_dir, still_dir):
    """Per frame of the two folders: canopy-demo --measure-foliage's columns as dicts."""
    cmd = [demo, "--measure-foliage", wind_dir, still_dir]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"wind_views: {' '.join(cmd)} exited {r.returncode}:\n{r.stdout[-2000:]}{r.stderr[-2000:]}")
    lines = r.stdout.splitlines()
    names = lines[1].split()
    rows = []
    for line in lines[2:]:
        parts = line.split()
        if len(parts) != len(names) or not parts[0].isdigit():
            continue
        rows.append({n: float(v) for n, v in zip(names, parts)})
    return rows


def measure(demo, out, scene_args, case_args, frames):
    wind_dir = os.path.join(out, "wind")
    still_dir = os.path.join(out, "still")
    common = scene_args + case_args + ["--frames", str(frames)]
    run_demo(demo, wind_dir, common)
    run_demo(demo, still_dir, common + ["--wind-speed", "0"])
    rows = measure_folders(demo, wind_dir, still_dir)
    return {"coverage": [r["coverage"] for r in rows], "offset": [r["offset_px"] for r in rows],
            "centroid": [r["top_x"] for r in rows], "sharpness": [r["sharpness"] for r in rows],
            "height_px": int(rows[0]["height"]) if rows else None}


def finite(v):
    return [x for x in v if math.isfinite(x)]


def corr(a, b):
    """Pearson's correlation of two series over the frames where both are finite."""
    pairs = [(x, y) for x, y in zip(a, b) if math.isfinite(x) and math.isfinite(y)]
    if len(pairs) < 2:
        return float("nan")
    ma = sum(p[0] for p in pairs) / len(pairs)
    mb = sum(p[1] for p in pairs) / len(pairs)
    sab = sum((x - ma) * (y - mb) for x, y in pairs)
    d = math.sqrt(sum((x - ma) ** 2 for x, _ in pairs) * sum((y - mb) ** 2 for _, y in pairs))
    return sab / d if d > 0 else float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("demo")
    ap.add_argument("out")
    ap.add_argument("--scenes", default="shrub,field")
    ap.add_argument("--methods", default="2d,per-vertex")
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--cases", default="orbit,mirror,yaw90,breeze")
    ap.add_argument("--extra", default="")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--json", default="")
    o = ap.parse_args()
    extra = o.extra.split() if o.extra else []
    # Frames per case: (orbit frames, degrees a frame), mirror, yaw90, breeze.
    orbit, mirror, yaw90, breeze = ((12, 30), 30, 10, 60) if o.quick else ((40, 9), 60, 60, 120)
    results, failures = [], []
    for scene in o.scenes.split(","):
        scene_args = ["--gltf", scene[5:]] if scene.startswith("gltf:") else ["--scene", scene]
        name = os.path.basename(scene[5:]) if scene.startswith("gltf:") else scene
        for method in o.methods.split(","):
            base = scene_args + ["--method", method, "--size", o.size] + extra
            row = {"scene": name, "method": method}
            tag = os.path.join(o.out, f"{name}_{method}")
            if "orbit" in o.cases:
                m = measure(o.demo, tag + "_orbit", base, ["--camera", "orbit", "--degrees-per-frame", str(orbit[1])], orbit[0])
                row["orbit_coverage_min"] = min(m["coverage"])
                row["orbit_coverage"] = m["coverage"]
                row["orbit_sharpness_min"] = min(m["sharpness"])
                if row["orbit_coverage_min"] < 0.9:
                    failures.append(f"{name} {method}: orbit coverage {row['orbit_coverage_min']:.3f} < 0.9")
            if "mirror" in o.cases:
                m0 = measure(o.demo, tag + "_yaw0", base, ["--yaw", "0"], mirror)
                m1 = measure(o.demo, tag + "_yaw180", base, ["--yaw", "180"], mirror)
                row["mirror_correlation"] = corr(m0["offset"], m1["offset"])
                row["yaw0_offset_mean"] = sum(finite(m0["offset"])) / max(len(finite(m0["offset"])), 1)
                row["yaw180_offset_mean"] = sum(finite(m1["offset"])) / max(len(finite(m1["offset"])), 1)
                if not row["mirror_correlation"] <= -0.6:
                    failures.append(f"{name} {method}: mirror correlation {row['mirror_correlation']:.3f} > -0.6")
            if "yaw90" in o.cases:
                m = measure(o.demo, tag + "_yaw90", base, ["--yaw", "90"], yaw90)
                row["yaw90_coverage_min"] = min(m["coverage"])
                if row["yaw90_coverage_min"] < 0.9:
                    failures.append(f"{name} {method}: yaw 90 coverage {row['yaw90_coverage_min']:.3f} < 0.9")
            if "breeze" in o.cases:
                m = measure(o.demo, tag + "_breeze", base, [], breeze)
                c = finite(m["centroid"])
                row["breeze_sway"] = (max(c) - min(c)) / max(m["height_px"] or 1, 1) if c else float("nan")
                row["breeze_height_px"] = m["height_px"]
            results.append(row)
            short = {k: (round(v, 3) if isinstance(v, float) else v) for k, v in row.items() if not isinstance(v, list)}
            print(json.dumps(short), flush=True)
    if o.json:
        with open(o.json, "w") as fh:
            json.dump(results, fh, indent=1)
    if o.check:
        for f in failures:
            print(f"wind_views: {f}")
        print(f"wind_views: {'FAILED' if failures else 'all within'} issue 66's bounds ({len(results)} runs)")
        sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
