#!/usr/bin/env python3
"""Puts canopy-game-host's frames (frame_NNNN.ppm in a folder) side by side, two per row, into one
PNG: `/usr/bin/python3 scripts/game_host_sheet.py DIR OUT.png [FRAME ...]` (default: every frame
in DIR, in order). Needs python3-matplotlib and numpy (scripts/deps.sh)."""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import numpy as np  # noqa: E402


def read_ppm(path):
    data = Path(path).read_bytes()
    magic, size, maxval, pixels = data.split(b"\n", 3)
    if magic != b"P6" or maxval != b"255":
        raise SystemExit(f"{path}: not an 8-bit binary PPM")
    w, h = map(int, size.split())
    return np.frombuffer(pixels, dtype=np.uint8)[: w * h * 3].reshape(h, w, 3)


def main():
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    folder, out = Path(sys.argv[1]), sys.argv[2]
    names = [f"frame_{int(n):04d}.ppm" for n in sys.argv[3:]] or sorted(p.name for p in folder.glob("frame_*.ppm"))
    images = [read_ppm(folder / n) for n in names]
    if not images:
        raise SystemExit(f"{folder}: no frame_NNNN.ppm")
    if len(images) % 2:
        images.append(np.zeros_like(images[0]))
    rows = [np.concatenate(images[i : i + 2], axis=1) for i in range(0, len(images), 2)]
    mpimg.imsave(out, np.concatenate(rows, axis=0))
    print(f"{out}: {len(names)} frames")


if __name__ == "__main__":
    main()
