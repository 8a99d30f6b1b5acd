#!/usr/bin/python3
"""A close-up before and after (issue 67; docs/performance.md "The picture in wind"): one frame of a
first-person walk through a scene, without wind, in wind as an older canopy-demo draws it, and in
wind as this one does, side by side and cropped so the leaves' pixels show.

Usage: scripts/closeup.py DEMO OUT.png [--before OLD_DEMO] [--before-label TEXT] [--scene-file demo/scenes/six_species.json]
       [--camera walk] [--size 480x320] [--frame 20] [--wind-speed 9] [--crop X,Y,W,H] [--zoom 2]
       [--extra "..."]
Without --before, the older picture is this demo's with `--sharpness 1 --max-stretch 0` (0.7's
filter and no stretch bound). Reads and writes PNGs with matplotlib (Debian's python3-matplotlib)."""
import argparse
import os
import tempfile

from matplotlib import image as mpimg
from matplotlib import pyplot as plt

from picture import run  # the same runner as the measure's: exits with the demo's output on failure


def frame(demo, out, args, index):
    """Frame `index` of a canopy-demo run (RGB in [0, 1])."""
    run([demo, "--out", out, "--no-mp4", "--frames", str(index + 1)] + args)
    return mpimg.imread(os.path.join(out, f"frame_{index:04d}.png"))[..., :3]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("demo")
    ap.add_argument("out")
    ap.add_argument("--before", default="")
    ap.add_argument("--before-label", default="before")
    ap.add_argument("--scene-file", default="demo/scenes/six_species.json")
    ap.add_argument("--camera", default="walk")
    ap.add_argument("--size", default="480x320")
    ap.add_argument("--frame", type=int, default=20)
    ap.add_argument("--wind-speed", default="9")
    ap.add_argument("--crop", default="")
    ap.add_argument("--zoom", type=float, default=2.0)
    ap.add_argument("--extra", default="")
    a = ap.parse_args()
    base = ["--scene-file", a.scene_file, "--camera", a.camera, "--size", a.size] + a.extra.split()
    wind = ["--wind-speed", a.wind_speed]
    with tempfile.TemporaryDirectory() as tmp:
        still = frame(a.demo, os.path.join(tmp, "still"), base + ["--wind-speed", "0"], a.frame)
        if a.before:
            old = frame(a.before, os.path.join(tmp, "before"), base + wind, a.frame)
            old_title = a.before_label
        else:
            old = frame(a.demo, os.path.join(tmp, "before"), base + wind + ["--sharpness", "1", "--max-stretch", "0"], a.frame)
            old_title = "bilinear, no stretch bound"
        new = frame(a.demo, os.path.join(tmp, "after"), base + wind, a.frame)
    if a.crop:
        x, y, w, h = (int(v) for v in a.crop.split(","))
        still, old, new = (im[y:y + h, x:x + w] for im in (still, old, new))
    h, w = still.shape[:2]
    fig, axes = plt.subplots(1, 3, figsize=(3 * w * a.zoom / 100.0, h * a.zoom / 100.0 + 0.5), dpi=100)
    for ax, im, title in zip(axes, (still, old, new), ("no wind", old_title, "this build")):
        ax.imshow(im, interpolation="nearest")
        ax.set_title(title, fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f"{os.path.basename(a.scene_file)}, --camera {a.camera}, frame {a.frame}, {a.wind_speed} m/s", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.out)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
