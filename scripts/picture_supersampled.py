#!/usr/bin/python3
"""Issue 67's lever "layers drawn above the screen's resolution", measured: canopy-demo draws a run
at FACTOR x the output size (layers, warp and composite all at that size), each frame is box-filtered
down to the output size, and the picture-in-wind measure (canopy-demo --measure-foliage: coverage
and sharpness, with wind against the same frame without) is taken on the filtered frames, beside
the same run drawn at the output size. Needs python3-numpy and python3-matplotlib (PNG I/O).

Usage: scripts/picture_supersampled.py DEMO OUT_DIR [--size 640x480] [--factor 2] [--frames 10]
       [--wind-speed 9] -- DEMO_SCENE_ARGS...   (e.g. -- --scene field --camera orbit --degrees-per-frame 9)
Prints one line per variant: sharpness median / least, coverage least."""
import argparse
import glob
import os
import subprocess
import sys

import matplotlib.image as mpimg
import numpy as np


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"picture_supersampled: {' '.join(cmd)} exited {r.returncode}:\n{r.stderr[-2000:]}")
    return r.stdout


def downsample(src, dst, factor):
    os.makedirs(dst, exist_ok=True)
    for path in sorted(glob.glob(os.path.join(src, "frame_*.png"))):
        im = mpimg.imread(path)[:, :, :3].astype(np.float64)
        h, w = im.shape[0] // factor, im.shape[1] // factor
        small = im[: h * factor, : w * factor].reshape(h, factor, w, factor, 3).mean(axis=(1, 3))
        mpimg.imsave(os.path.join(dst, os.path.basename(path)), np.clip(small, 0.0, 1.0))


def measure(demo, wind, still):
    lines = run([demo, "--measure-foliage", wind, still]).splitlines()
    names = lines[1].split()
    rows = [dict(zip(names, map(float, l.split()))) for l in lines[2:] if l.split() and l.split()[0].isdigit()]
    rows = [r for r in rows if r["still_px"] > 0]
    sharp = sorted(r["sharpness"] for r in rows)
    return sharp[len(sharp) // 2], sharp[0], min(r["coverage"] for r in rows)


def main():
    argv = sys.argv[1:]
    scene = argv[argv.index("--") + 1:] if "--" in argv else []
    argv = argv[: argv.index("--")] if "--" in argv else argv
    ap = argparse.ArgumentParser()
    ap.add_argument("demo")
    ap.add_argument("out")
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--factor", type=int, default=2)
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument("--wind-speed", default="9")
    o = ap.parse_args(argv)
    w, h = map(int, o.size.split("x"))
    big = f"{w * o.factor}x{h * o.factor}"
    for label, size in (("at the output size", o.size), (f"at {o.factor}x, box-filtered down", big)):
        tag = os.path.join(o.out, size)
        for wind in ("wind", "still"):
            speed = o.wind_speed if wind == "wind" else "0"
            run([o.demo, "--out", f"{tag}_{wind}", "--size", size, "--frames", str(o.frames), "--wind-speed", speed, "--no-mp4"] + scene)
        if size != o.size:
            for wind in ("wind", "still"):
                downsample(f"{tag}_{wind}", f"{tag}_{wind}_down", o.factor)
            med, least, cov = measure(o.demo, f"{tag}_wind_down", f"{tag}_still_down")
        else:
            med, least, cov = measure(o.demo, f"{tag}_wind", f"{tag}_still")
        print(f"{' '.join(scene)} {o.wind_speed} m/s, {label}: sharpness median {med:.3f} least {least:.3f}, coverage least {cov:.3f}",
              flush=True)


if __name__ == "__main__":
    main()
