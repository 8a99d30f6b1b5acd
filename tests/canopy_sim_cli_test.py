#!/usr/bin/env python3
"""Issue 69: canopy-sim on the tiled field. Runs `canopy-sim` with a strong left wind for 300 steps
and checks what it wrote: the three .npy files (wind, vs, tiled) each float32 of shape [N, N, 2]
with finite values, the printed means no larger than the printed maxima, and tiled.npy the
tiling of vs.npy with seam blending as docs/design.md "Conventions where the paper is silent"
states it and compute/sim_reference.cpp `tile` computes it: per axis T = w S(x) + (1 - w)
S(x + N/2), w = 1 - 2 |(i + 0.5)/N - 0.5|. Pure Python (no numpy on CI's interpreter)."""
import ast
import math
import os
import re
import struct
import subprocess
import sys
import tempfile

TOLERANCE = 1e-5  # float32 sums in another order


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def read_npy(path):
    with open(path, "rb") as fh:
        data = fh.read()
    if data[:6] != b"\x93NUMPY":
        fail(f"{path}: not an .npy file")
    major = data[6]
    if major == 1:
        hlen = struct.unpack("<H", data[8:10])[0]
        start = 10
    else:
        hlen = struct.unpack("<I", data[8:12])[0]
        start = 12
    header = ast.literal_eval(data[start:start + hlen].decode("latin1"))
    if header.get("descr") != "<f4" or header.get("fortran_order"):
        fail(f"{path}: header {header} is not little-endian float32 in C order")
    shape = tuple(header["shape"])
    body = data[start + hlen:]
    count = len(body) // 4
    values = struct.unpack(f"<{count}f", body[:4 * count])
    expected = 1
    for s in shape:
        expected *= s
    if count != expected:
        fail(f"{path}: shape {shape} holds {expected} values, the file {count}")
    return shape, values


def tile_weight(i, n):
    return 1.0 - abs((i + 0.5) / n - 0.5) * 2.0


def main():
    sim = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "sim")
        cmd = [sim, "--steps", "300", "--wind", "left", "--strength", "5", "--frequency", "0.5", "--dt", "0.033", "--out", out]
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=1200)
        print(r.stdout + r.stderr)
        if r.returncode != 0:
            fail(f"{' '.join(cmd)} exited {r.returncode}")
        # The printed summary: each field's mean no larger than its maximum magnitude.
        for m in re.finditer(r"(\w+)\s+mean \(([-+0-9.]+), ([-+0-9.]+)\), max \|v\| ([0-9.]+)", r.stdout):
            name, mx, my, vmax = m.group(1), float(m.group(2)), float(m.group(3)), float(m.group(4))
            if math.hypot(mx, my) > vmax + 1e-3:
                fail(f"{name}: printed mean ({mx}, {my}) is larger than its max |v| {vmax}")
        fields = {}
        for name in ("wind", "vs", "tiled"):
            shape, values = read_npy(os.path.join(out, name + ".npy"))
            if len(shape) != 3 or shape[0] != shape[1] or shape[2] != 2:
                fail(f"{name}.npy: shape {shape}, expected [N, N, 2]")
            if not all(math.isfinite(v) for v in values):
                fail(f"{name}.npy: non-finite values")
            fields[name] = (shape, values)
        n = fields["vs"][0][0]
        for name, (shape, _) in fields.items():
            if shape != (n, n, 2):
                fail(f"{name}.npy: shape {shape}, vs.npy {(n, n, 2)}")
        S, T = fields["vs"][1], fields["tiled"][1]
        if max(abs(v) for v in S) == 0.0:
            fail("vs.npy is all zero after 300 steps of wind")
        half, worst = n // 2, 0.0
        for j in range(n):
            wy = tile_weight(j, n)
            j2 = (j + half) % n
            for i in range(n):
                wx = tile_weight(i, n)
                i2 = (i + half) % n
                for k in range(2):
                    t = wy * (wx * S[2 * (j * n + i) + k] + (1 - wx) * S[2 * (j * n + i2) + k]) + \
                        (1 - wy) * (wx * S[2 * (j2 * n + i) + k] + (1 - wx) * S[2 * (j2 * n + i2) + k])
                    worst = max(worst, abs(t - T[2 * (j * n + i) + k]))
        scale = max(abs(v) for v in S)
        print(f"tiled.npy against the tiling of vs.npy: max |difference| {worst:.3g} (max |vs| {scale:.4g})")
        if worst > TOLERANCE * max(1.0, scale):
            fail(f"tiled.npy differs from the tiling of vs.npy by {worst} (tolerance {TOLERANCE * max(1.0, scale)})")
    print("canopy-sim's three fields: shapes, finite values and the tiling hold")


if __name__ == "__main__":
    main()
