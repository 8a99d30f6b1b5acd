#!/usr/bin/env python3
"""canopy-game-host's character parts the grass (ctest GameHost): frames of a run with the character
given to Canopy as a pusher (A) against a run without (B), both with --no-leaves; pixels whose colour
differs by more than 8 levels, inside the band where the push may reach (A/band_NNNN.pgm: pixels
whose world point lies within 3 radii of where the character has walked, written by the host from
its depth) and beyond it. Prints one line; exit 1 unless some differ inside and at most `max_beyond`
percent of the differing pixels lie beyond.
    game_host_push.py A B [max_beyond]"""
import os
import sys


def read_ppm(path):
    with open(path, 'rb') as f:
        data = f.read()
    parts = data.split(b'\n', 3)
    w, h = map(int, parts[1].split())
    return w, h, parts[3]


def main():
    a, b = sys.argv[1], sys.argv[2]
    max_beyond = float(sys.argv[3]) if len(sys.argv) > 3 else 5.0
    inside = beyond = frames = 0
    for name in sorted(os.listdir(a)):
        if not (name.startswith('frame_') and name.endswith('.ppm')) or not os.path.exists(os.path.join(b, name)):
            continue
        w, h, pa = read_ppm(os.path.join(a, name))
        _, _, pb = read_ppm(os.path.join(b, name))
        band_name = os.path.join(a, name.replace('frame_', 'band_').replace('.ppm', '.pgm'))
        with open(band_name, 'rb') as f:
            band = f.read().split(b'\n', 3)[3]
        frames += 1
        for k in range(w * h):
            if max(abs(pa[3 * k + c] - pb[3 * k + c]) for c in range(3)) <= 8:
                continue
            if band[k]:
                inside += 1
            else:
                beyond += 1
    share = 100.0 * beyond / max(inside + beyond, 1)
    print(f"character push: {frames} frames, {inside} pixels differ by > 8 levels within 3 radii of where it walked, "
          f"{beyond} beyond ({share:.2f} % of the differing pixels beyond)")
    return 0 if frames > 0 and inside > 0 and share <= max_beyond else 1


if __name__ == '__main__':
    sys.exit(main())
