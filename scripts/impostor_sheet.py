#!/usr/bin/env python3
"""The impostor debug picture (docs/impostors_debug.png) from `canopy-bench impostors --images DIR`.

usage: /usr/bin/python3 scripts/impostor_sheet.py DIR FACES OUT.png

Four panels: the 'across' camera's debug view (scaled to half), the 'distant' camera's debug view,
its far layers with every leaf and with impostors by projected size (those three cropped around
the field and scaled by 1.8). Needs Pillow (python3-pil, a dependency of python3-matplotlib).
"""
import sys

from PIL import Image, ImageDraw


def main(argv):
    if len(argv) != 4:
        sys.exit(__doc__)
    folder, faces, out = argv[1], argv[2], argv[3]

    def crop(name):
        im = Image.open(f"{folder}/{name}").convert("RGB").crop((368, 296, 656, 476))
        return im.resize((512, 320), Image.LANCZOS)

    def full(name):
        return Image.open(f"{folder}/{name}").convert("RGB").resize((512, 384), Image.LANCZOS)

    panels = [
        (full(f"impostors_debug_across_{faces}.png"), "across: debug view, no box below 64 px: all leaves"),
        (crop(f"impostors_debug_distant_{faces}.png"), "distant (crop x1.8): debug view, by projected size"),
        (crop(f"impostors_distant_{faces}_off.png"), "distant: far layers, every leaf"),
        (crop(f"impostors_distant_{faces}_size.png"), "distant: far layers, impostors by projected size"),
    ]
    sheet = Image.new("RGB", (1024, 2 * 384 + 2 * 20), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for i, (im, label) in enumerate(panels):
        x, y = (i % 2) * 512, (i // 2) * (384 + 20)
        sheet.paste(im, (x, y + 20 + (384 - im.size[1]) // 2))
        draw.text((x + 6, y + 4), label, fill=(0, 0, 0))
    sheet.save(out, optimize=True)


if __name__ == "__main__":
    main(sys.argv)
