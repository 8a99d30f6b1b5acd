#!/usr/bin/python3
"""The wind seen from every side (issue 66): runs canopy-demo on a scene with the wind and without it
(--strength 0 as the demo's still reference: the same cameras and times) and measures each frame.

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
       [--methods 2d,per-vertex] [--extra "--wind-speed 9"] [--json FILE]
Reads PNGs with numpy + matplotlib (Debian's python3-numpy, python3-matplotlib)."""
import argparse
import json
import os
import subprocess
import sys

import numpy as np
from matplotlib import image as mpimg


def run_demo(demo, out, args):
    cmd = [demo, "--out", out, "--no-mp4"] + args
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"wind_views: {' '.join(cmd)} exited {r.returncode}:\n{r.stdout[-2000:]}{r.stderr[-2000:]}")
    return sorted(f for f in os.listdir(out) if f.startswith("frame_") and f.endswith(".png"))


def foliage_of(img):
    """The foliage pixels of an RGB(A) image in [0, 1]: green above red and blue by 15 levels."""
    rgb = (img[..., :3] * 255.0).astype(np.int32)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return (g > r + 15) & (g > b + 15)


def foliage(path):
    return foliage_of(mpimg.imread(path))


def top_centroid(mask, rows):
    lo, hi = rows
    m = mask[lo:hi]
    ys, xs = np.nonzero(m)
    return float(xs.mean()) if len(xs) else float("nan")


def measure(demo, out, scene_args, case_args, frames):
    wind_dir = os.path.join(out, "wind")
    still_dir = os.path.join(out, "still")
    common = scene_args + case_args + ["--frames", str(frames)]
    fw = run_demo(demo, wind_dir, common)
    fs = run_demo(demo, still_dir, common + ["--wind-speed", "0"])
    cov, off, cx = [], [], []
    height_px = None
    for a, b in zip(fw, fs):
        mw, ms = foliage(os.path.join(wind_dir, a)), foliage(os.path.join(still_dir, b))
        n_still = int(ms.sum())
        cov.append(float(mw.sum()) / max(n_still, 1))
        rows = np.nonzero(ms.any(axis=1))[0]
        if len(rows) == 0:
            off.append(float("nan"))
            cx.append(float("nan"))
            continue
        top, bottom = int(rows[0]), int(rows[-1]) + 1
        third = (top, top + max(1, (bottom - top) // 3))
        if height_px is None:
            height_px = bottom - top
        w, s = top_centroid(mw, third), top_centroid(ms, third)
        off.append(w - s)
        cx.append(w)
    return {"coverage": cov, "offset": off, "centroid": cx, "height_px": height_px}


def corr(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    ok = np.isfinite(a) & np.isfinite(b)
    a, b = a[ok] - a[ok].mean(), b[ok] - b[ok].mean()
    d = np.sqrt((a * a).sum() * (b * b).sum())
    return float((a * b).sum() / d) if d > 0 else float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("demo")
    ap.add_argument("out")
    ap.add_argument("--scenes", default="shrub,field")
    ap.add_argument("--methods", default="2d,per-vertex")
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--cases", default="orbit,mirror,yaw90,breeze")
    ap.add_argument("--extra", default="")
    ap.add_argument("--json", default="")
    o = ap.parse_args()
    extra = o.extra.split() if o.extra else []
    results = []
    for scene in o.scenes.split(","):
        scene_args = ["--gltf", scene[5:]] if scene.startswith("gltf:") else ["--scene", scene]
        name = os.path.basename(scene[5:]) if scene.startswith("gltf:") else scene
        for method in o.methods.split(","):
            base = scene_args + ["--method", method, "--size", o.size] + extra
            row = {"scene": name, "method": method}
            tag = os.path.join(o.out, f"{name}_{method}")
            if "orbit" in o.cases:
                m = measure(o.demo, tag + "_orbit", base, ["--camera", "orbit", "--degrees-per-frame", "9"], 40)
                row["orbit_coverage_min"] = min(m["coverage"])
                row["orbit_coverage"] = m["coverage"]
            if "mirror" in o.cases:
                m0 = measure(o.demo, tag + "_yaw0", base, ["--yaw", "0"], 60)
                m1 = measure(o.demo, tag + "_yaw180", base, ["--yaw", "180"], 60)
                row["mirror_correlation"] = corr(m0["offset"], m1["offset"])
                row["yaw0_offset_mean"] = float(np.nanmean(m0["offset"]))
                row["yaw180_offset_mean"] = float(np.nanmean(m1["offset"]))
            if "yaw90" in o.cases:
                m = measure(o.demo, tag + "_yaw90", base, ["--yaw", "90"], 60)
                row["yaw90_coverage_min"] = min(m["coverage"])
            if "breeze" in o.cases:
                m = measure(o.demo, tag + "_breeze", base, [], 120)
                c = np.asarray(m["centroid"], float)
                row["breeze_sway"] = float((np.nanmax(c) - np.nanmin(c)) / max(m["height_px"] or 1, 1))
                row["breeze_height_px"] = m["height_px"]
            results.append(row)
            short = {k: (round(v, 3) if isinstance(v, float) else v) for k, v in row.items() if not isinstance(v, list)}
            print(json.dumps(short), flush=True)
    if o.json:
        with open(o.json, "w") as fh:
            json.dump(results, fh, indent=1)


if __name__ == "__main__":
    main()
