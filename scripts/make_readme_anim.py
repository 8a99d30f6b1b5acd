#!/usr/bin/python3
"""The README's animated picture: the demo's frames of the shrub in wind as a looping GIF.

    bash scripts/run.sh --out demo_out            # 60 frames of the default shrub, 640x480
    /usr/bin/python3 scripts/make_readme_anim.py demo_out docs/canopy_wind.gif

Crops every frame to the vegetation (the union over all frames of the pixels that differ from the
first frame's corner colour, plus a margin), scales it to --width pixels, keeps every --every'th
frame (each shown as long as the demo frames it stands for, at the demo's 30 frames per second) on
one palette made from all frames (no palette flicker); a pixel that did not change is written
transparent over the frame before, which keeps the file small. Needs Pillow
(python3-pil; third_party_notes/pillow.md).
"""
import argparse
import glob
import os
import sys

from PIL import Image, ImageChops


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("frames", help="folder with frame_0000.png ... (canopy-demo --out)")
    ap.add_argument("out", help="the GIF to write")
    ap.add_argument("--width", type=int, default=260, help="output width in pixels (default 260)")
    ap.add_argument("--every", type=int, default=3, help="keep every Nth frame, shown N times as long (default 3)")
    ap.add_argument("--colors", type=int, default=32, help="palette size (default 32)")
    ap.add_argument("--margin", type=int, default=12, help="pixels kept around the vegetation (default 12)")
    args = ap.parse_args()
    paths = sorted(glob.glob(os.path.join(args.frames, "frame_*.png")))[::max(1, args.every)]
    if not paths:
        sys.exit(f"make_readme_anim: no frame_*.png in {args.frames}")
    frames = [Image.open(p).convert("RGB") for p in paths]
    w, h = frames[0].size
    background = Image.new("RGB", (w, h), frames[0].getpixel((0, 0)))
    box = None
    for f in frames:
        b = ImageChops.difference(f, background).convert("L").point(lambda v: 255 if v > 8 else 0).getbbox()
        if b:
            box = b if box is None else (min(box[0], b[0]), min(box[1], b[1]), max(box[2], b[2]), max(box[3], b[3]))
    if box is None:
        sys.exit("make_readme_anim: the frames show nothing but the background")
    m = args.margin
    box = (max(0, box[0] - m), max(0, box[1] - m), min(w, box[2] + m), min(h, box[3] + m))
    scale = args.width / (box[2] - box[0])
    size = (args.width, max(1, round((box[3] - box[1]) * scale)))
    small = [f.crop(box).resize(size, Image.LANCZOS) for f in frames]
    # One palette for every frame: quantise a strip of all frames together.
    strip = Image.new("RGB", (size[0], size[1] * len(small)))
    for i, f in enumerate(small):
        strip.paste(f, (0, i * size[1]))
    palette = strip.quantize(colors=args.colors, method=Image.MEDIANCUT)
    out = [f.quantize(palette=palette, dither=Image.NONE) for f in small]
    # After the first frame, a pixel whose palette index did not change is written as the
    # transparent index (disposal 1 keeps the frame below): long runs that LZW packs well.
    clear = args.colors
    pal = palette.getpalette()[:3 * args.colors] + [255, 0, 255]
    shown = out[0].tobytes()
    deltas = []
    for f in out[1:]:
        now = f.tobytes()
        delta = Image.frombytes("P", size, bytes(c if c != p else clear for c, p in zip(now, shown)))
        delta.putpalette(pal)
        deltas.append(delta)
        shown = now
    first = out[0].copy()
    first.putpalette(pal)
    first.save(args.out, save_all=True, append_images=deltas, duration=round(1000 * max(1, args.every) / 30), loop=0,
               transparency=clear, disposal=1, optimize=False)
    print(f"wrote {args.out}: {len(out)} frames, {size[0]}x{size[1]} (crop x {box[0]}..{box[2]}, "
          f"y {box[1]}..{box[3]} of {w}x{h}), {os.path.getsize(args.out) // 1024} KiB")


if __name__ == "__main__":
    main()
