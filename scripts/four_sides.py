#!/usr/bin/python3
"""The same vegetation seen from four sides in the same world wind (issue 66; docs/performance.md
"The wind from every side"): canopy-demo at --yaw 0, 90, 180 and 270 with the library's default wind
and with --wind-speed 0, the same frame of each; one picture, the wind's row above the still row,
and under each pair the share of foliage pixels the wind kept (foliage: green above red and blue by
15 levels: canopy-demo --measure-foliage, as scripts/wind_views.py measures).

Usage: scripts/four_sides.py DEMO OUT.png [--scene field] [--size 320x240] [--frame 29]
       [--method 2d] [--extra "--wind-dir 0,0,1"]
Reads and writes PNGs with matplotlib (Debian's python3-matplotlib)."""
import argparse
import os
import tempfile

from matplotlib import image as mpimg
from matplotlib import pyplot as plt

from wind_views import measure_folders, run_demo  # the same measure and runner as the table's


def frame(demo, out, args, index):
    """Frame `index` of a canopy-demo run (RGB in [0, 1])."""
    run_demo(demo, out, ["--frames", str(index + 1)] + args)
    return mpimg.imread(os.path.join(out, f"frame_{index:04d}.png"))[..., :3]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("demo")
    ap.add_argument("out")
    ap.add_argument("--scene", default="field")
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--frame", type=int, default=29)
    ap.add_argument("--method", default="2d")
    ap.add_argument("--extra", default="")
    a = ap.parse_args()
    base = ["--scene", a.scene, "--size", a.size, "--method", a.method] + a.extra.split()
    fig, axes = plt.subplots(2, 4, figsize=(12, 5.2))
    with tempfile.TemporaryDirectory() as tmp:
        for k, yaw in enumerate((0, 90, 180, 270)):
            wind = frame(a.demo, os.path.join(tmp, f"w{yaw}"), base + ["--yaw", str(yaw)], a.frame)
            still = frame(a.demo, os.path.join(tmp, f"s{yaw}"), base + ["--yaw", str(yaw), "--wind-speed", "0"], a.frame)
            kept = measure_folders(a.demo, os.path.join(tmp, f"w{yaw}"), os.path.join(tmp, f"s{yaw}"))[a.frame]["coverage"]
            axes[0, k].imshow(wind)
            axes[0, k].set_title(f"yaw {yaw}°, wind")
            axes[1, k].imshow(still)
            axes[1, k].set_title(f"yaw {yaw}°, no wind")
            axes[1, k].set_xlabel(f"foliage kept {kept:.2f}")
            print(f"yaw {yaw:3d}: foliage pixels with wind / without {kept:.3f}")
    for ax in axes.flat:
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f"canopy-demo --scene {a.scene} --method {a.method}, frame {a.frame}: the library's default wind "
                 f"(3 m/s toward +X) from four sides")
    fig.tight_layout()
    fig.savefig(a.out, dpi=80)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
