#!/usr/bin/python3
"""The real plants in wind, a gallery (issue 77): docs/gallery.md and its sheets in docs/gallery/.

For each real plant of ../shared/assets, canopy-demo's frame without wind beside the same frame in a
breeze (3 m/s) and in a gale (9 m/s): the 2D method before (the paper's still rigid background and
leaf roots: --rigid-motion still --paper-roots), the 2D method now, and the per-vertex baseline.
Then CommonTree_3 orbited without wind (frames 12-20 of --camera orbit --degrees-per-frame 9) with
Habel's lobe at 0.25 (--leaf-roughness 0.25, before) and with the file's own roughness (now): the
share of foliage pixels that are pale (saturation <= 0.3, value >= 150), per frame.

Usage: /usr/bin/python3 scripts/plants_gallery.py DEMO [--assets DIR] [--docs DIR] [--size WxH]
       [--frame N] [--plants NAME,...] [--work DIR [--reuse]]
  DEMO       canopy-demo (build/release/canopy-demo)
  --assets   the assets folder (default ../shared/assets; absent: exits 0 with a message)
  --docs     where gallery.md and gallery/ are written (default docs)
  --frame    the frame shown, of --frame + 1 rendered (default 23: frame 23 of --frames 24)
Needs python3-pil (scripts/deps.sh)."""
import argparse
import os
import subprocess
import sys
import tempfile

from PIL import Image, ImageDraw

# (name in the page, file under the assets folder)
PLANTS = [
    ("CommonTree_3", "quaternius_megakit_common_tree_3/CommonTree_3.gltf"),
    ("CommonTree_1", "quaternius_CommonTree_1/CommonTree_1.glb"),
    ("PineTree_1", "quaternius_PineTree_1/PineTree_1.glb"),
    ("PS1 pine", "sketchfab_pine_ps1_wersaus33/scene.gltf"),
    ("DiffuseTransmissionPlant", "DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf"),
    ("fern_02", "fern_02/fern_02.glb"),
    ("KayKit Tree_1_C", "kaykit_tree_1_c/Tree_1_C_Color1.gltf"),
    ("Kenney palm", "kenney_nature_palm_tall/tree_palmTall.glb"),
    ("flower bushes", "polypizza_flower_bushes/flower_bushes.glb"),
    ("Quaternius grass", "quaternius_Grass/Grass.glb"),
]
WINDS = [("breeze", "3"), ("gale", "9")]
COLUMNS = [
    ("no wind", None),
    ("2D before", ["--rigid-motion", "still", "--paper-roots"]),
    ("2D now", []),
    ("per-vertex", ["--method", "per-vertex"]),
]


REUSE = False  # --reuse: keep the frames a run of --work already wrote


def run_demo(demo, out, args):
    if REUSE and os.path.exists(os.path.join(out, "frame_0000.png")):
        return
    cmd = [demo, "--out", out, "--no-mp4"] + args
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"plants_gallery: {' '.join(cmd)} exited {r.returncode}:\n{r.stdout[-2000:]}{r.stderr[-2000:]}")


def frame(out, n):
    path = os.path.join(out, f"frame_{n:04d}.png")
    if not os.path.exists(path):
        sys.exit(f"plants_gallery: {path} was not written")
    return Image.open(path).convert("RGB")


def labelled(img, text):
    img = img.copy()
    d = ImageDraw.Draw(img)
    d.rectangle([0, 0, 7 * len(text) + 6, 14], fill=(0, 0, 0))
    d.text((3, 2), text, fill=(255, 255, 255))
    return img


def sheet(rows):
    w, h = rows[0][0].size
    out = Image.new("RGB", (w * max(len(r) for r in rows), h * len(rows)), (0, 0, 0))
    for y, r in enumerate(rows):
        for x, img in enumerate(r):
            out.paste(img, (x * w, y * h))
    return out


def whitish_share(img):
    """Pale foliage share: pixels of saturation (max - min) / max <= 0.3 and value max >= 150 (the
    whitish sheen of a glossy lobe on green leaves; the bark is saturated brown), over the pixels
    that are not the sky (the frame's top-left pixel's colour, +-3 levels)."""
    px = img.load()
    sky = px[0, 0]
    fol = white = 0
    for y in range(img.size[1]):
        for x in range(img.size[0]):
            p = px[x, y]
            if max(abs(p[c] - sky[c]) for c in range(3)) <= 3:
                continue
            fol += 1
            hi, lo = max(p), min(p)
            if hi >= 150 and (hi - lo) <= 0.3 * hi:
                white += 1
    return white / fol if fol else 0.0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("demo")
    ap.add_argument("--assets", default="../shared/assets")
    ap.add_argument("--docs", default="docs")
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--frame", type=int, default=23)
    ap.add_argument("--plants", default="")
    ap.add_argument("--work", default="")
    ap.add_argument("--reuse", action="store_true", help="keep the frames a run of --work already wrote")
    a = ap.parse_args()
    global REUSE
    REUSE = a.reuse
    if not os.path.isdir(a.assets):
        print(f"plants_gallery: {a.assets} is absent: no gallery made")
        return 0
    wanted = [p for p in a.plants.split(",") if p]
    work = a.work or tempfile.mkdtemp(prefix="canopy_gallery_")
    gdir = os.path.join(a.docs, "gallery")
    os.makedirs(gdir, exist_ok=True)
    common = ["--size", a.size, "--frames", str(a.frame + 1)]
    md = []
    for name, rel in PLANTS:
        if wanted and name not in wanted:
            continue
        path = os.path.join(a.assets, rel)
        if not os.path.exists(path):
            print(f"plants_gallery: {path} is absent, skipped")
            continue
        key = name.replace(" ", "_")
        still_dir = os.path.join(work, key, "still")
        run_demo(a.demo, still_dir, ["--gltf", path, "--wind-speed", "0"] + common)
        still = frame(still_dir, a.frame)
        rows = []
        for wind, speed in WINDS:
            row = [labelled(still, f"{wind}: no wind")]
            for col, extra in COLUMNS[1:]:
                d = os.path.join(work, key, f"{wind}_{col.replace(' ', '_')}")
                run_demo(a.demo, d, ["--gltf", path, "--wind-speed", speed] + extra + common)
                row.append(labelled(frame(d, a.frame), f"{wind} {speed} m/s: {col}"))
            rows.append(row)
        out = os.path.join(gdir, f"{key}.jpg")
        sheet(rows).save(out, quality=85)
        print(f"{out}: {name}")
        md.append(f"### {name}\n\n`{rel}`\n\n![{name} in a breeze and a gale](gallery/{key}.jpg)\n")
    # The orbit's blotches: Habel's lobe at 0.25 against the file's roughness.
    blotch = []
    ct3 = os.path.join(a.assets, PLANTS[0][1])
    if os.path.exists(ct3) and (not wanted or PLANTS[0][0] in wanted):
        orbit = ["--gltf", ct3, "--wind-speed", "0", "--camera", "orbit", "--degrees-per-frame", "9",
                 "--frames", "21", "--size", a.size]
        cells = []
        for label, extra in [("--leaf-roughness 0.25 (before)", ["--leaf-roughness", "0.25"]), ("the file's roughness (now)", [])]:
            d = os.path.join(work, "orbit_" + ("before" if extra else "now"))
            run_demo(a.demo, d, orbit + extra)
            shares = [whitish_share(frame(d, n)) for n in range(12, 21)]
            blotch.append((label, shares))
            cells.append([labelled(frame(d, n), f"frame {n}: {'before' if extra else 'now'}") for n in (12, 14, 16, 18, 20)])
        out = os.path.join(gdir, "CommonTree_3_orbit.jpg")
        sheet(cells).save(out, quality=85)
        print(f"{out}: CommonTree_3's orbit")
    page = [
        "# Real plants in wind: a gallery",
        "",
        "Made by `/usr/bin/python3 scripts/plants_gallery.py build/release/canopy-demo` (issue 77; needs",
        "../shared/assets): canopy-demo at " + a.size + ", frame " + str(a.frame) + " of --frames " + str(a.frame + 1) + ", the default camera. Each",
        "sheet: the frame without wind, then the same frame in a breeze (3 m/s, top row) and a gale (9 m/s,",
        "bottom row) drawn by the 2D method *before* (the paper's still trunks and branches and its leaf",
        "roots, `--rigid-motion still --paper-roots`, on today's build), the 2D method *now*, and the",
        "per-vertex baseline (`--method per-vertex`). The measures behind them are `canopy-bench plants`'",
        "(docs/performance.md \"Real plants in wind\"; docs/design.md \"Rigid parts in wind\").",
        "",
    ]
    page += md
    if blotch:
        page += [
            "### CommonTree_3's orbit without wind: the leaves' gloss",
            "",
            "Frames 12, 14, 16, 18, 20 of `--camera orbit --degrees-per-frame 9`: top, Habel's lobe at",
            "roughness 0.25 (`--leaf-roughness 0.25`, what every leaf got before); bottom, the file's own",
            "(roughnessFactor 1). Pale foliage pixels (saturation <= 0.3, value >= 150 of 255), frames 12-20:",
            "",
            "| gloss | pale share, frames 12-20 (max) |",
            "|---|---|",
        ]
        for label, shares in blotch:
            page.append(f"| {label} | {' '.join(f'{s:.3f}' for s in shares)} ({max(shares):.3f}) |")
        page += ["", "![CommonTree_3's orbit, before and now](gallery/CommonTree_3_orbit.jpg)", ""]
    page += [
        "### The golden images, before and now",
        "",
        "ctest `Scenes/GoldenTest` (tests/golden/, the generated crown in the plane's side wind, 1.5 domain",
        "units/s): before issue 77 (b2535fa) the trunk stood still under its swaying crown; now it bends",
        "with it from its standing foot. Made by `git show b2535fa:tests/golden/NAME.png` beside the",
        "current file (the images are the tests' own).",
        "",
        "![The golden images before and now](gallery/goldens_before_after.png)",
        "",
    ]
    if not wanted:
        with open(os.path.join(a.docs, "gallery.md"), "w") as f:
            f.write("\n".join(page))
        print(f"{os.path.join(a.docs, 'gallery.md')}: written")
    for label, shares in blotch:
        print(f"pale share, {label}: max {max(shares):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
