#!/usr/bin/python3
"""Draws canopy-bench table1's scaling series (CSV from --series --csv-dir DIR) as PNG plots with
Debian's python3-matplotlib (apt-get install python3-matplotlib).

    /usr/bin/python3 scripts/plot_bench.py DIR OUT_PREFIX [TITLE]

writes OUT_PREFIX_faces.png, OUT_PREFIX_layers.png and OUT_PREFIX_resolution.png: the whole-frame
median (line) and p95 (shaded up to it) against face count, layer count and pixel count.

    /usr/bin/python3 scripts/plot_bench.py --pervertex CSV OUT_PNG [TITLE]

draws canopy-bench pervertex's CSV (--csv): the 2D method (still and turning camera) and the
per-vertex baseline against face count, and the baseline / 2D ratios.

    /usr/bin/python3 scripts/plot_bench.py --camera CSV OUT_PNG [TITLE]

draws canopy-bench camera's per-frame CSV (--csv): per face count and path, the frame time along the
path with the layers reprojected and re-sliced by their error (re-slice frames marked) and re-sliced
every frame, beside the still camera's median; below, the world-lock error of each frame against the
every-frame reference (coverage IoU and mean silhouette distance).

    /usr/bin/python3 scripts/plot_bench.py --layercount CSV OUT_PNG [TITLE]

draws canopy-bench layercount's CSV (--csv): per model, the equal-layer layouts' colour difference
against the 16-layer reference relative to the wind's own motion, and their coverage IoU, against the
layer count; the paper's 3(1-1-1) and 5(3-1-1) as points."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SERIES = {
    "faces": ("faces (log scale)", True),
    "layers": ("layers (n(n-2-1-1) layouts; 1(1-0-0), 2(1-1-0))", False),
    "resolution": ("pixels", False),
}


def plot_pervertex(path, out, title):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    faces = [float(r["faces"]) for r in rows]
    fig, (ax, rx) = plt.subplots(1, 2, figsize=(9.0, 3.6), dpi=100)
    series = [("2d_still", "2D method, still camera"), ("2d_turning", "2D method, camera turning (re-slice every frame)"),
              ("per_vertex", "per-vertex baseline (Habel; wind field)")]
    if "per_vertex_uniform_ms" in rows[0]:
        series.append(("per_vertex_uniform", "per-vertex baseline, uniform wind (before 0.7)"))
    for key, label in series:
        med = [float(r[key + "_ms"]) for r in rows]
        p95 = [float(r[key + "_p95"]) for r in rows]
        ax.plot(faces, med, marker="o", label=label)
        ax.fill_between(faces, med, p95, alpha=0.2)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("faces (log scale)")
    ax.set_ylabel("whole frame, ms (wall, log scale)")
    ax.set_title("%s: frame vs faces" % title, fontsize=9)
    ax.grid(True, alpha=0.3, which="both")
    ax.legend(fontsize=7)
    still = [float(r["per_vertex_ms"]) / float(r["2d_still_ms"]) for r in rows]
    turning = [float(r["per_vertex_ms"]) / float(r["2d_turning_ms"]) for r in rows]
    rx.plot(faces, still, marker="o", label="per-vertex / 2D still")
    rx.plot(faces, turning, marker="s", label="per-vertex / 2D turning")
    for series in (still, turning):
        for xi, yi in zip(faces, series):
            rx.annotate("%.2fx" % yi, (xi, yi), textcoords="offset points", xytext=(0, 6), ha="center", fontsize=7)
    rx.axhline(1.0, color="grey", lw=0.8)
    rx.set_xscale("log")
    rx.set_yscale("log")
    rx.set_xlabel("faces (log scale)")
    rx.set_ylabel("baseline / 2D (log; > 1: 2D cheaper)")
    rx.grid(True, alpha=0.3)
    rx.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out)
    print("wrote", out)


def plot_camera(path, out, title):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    faces = sorted({int(r["faces"]) for r in rows})
    paths = [p for p in dict.fromkeys(r["path"] for r in rows) if p != "still"]
    fig, axes = plt.subplots(2, len(faces), figsize=(5.6 * len(faces), 6.4), dpi=100, squeeze=False)
    for col, n in enumerate(faces):
        ax, ex = axes[0][col], axes[1][col]
        still = sorted(float(r["auto_ms"]) for r in rows if int(r["faces"]) == n and r["path"] == "still")
        if still:
            ax.axhline(still[len(still) // 2], color="black", lw=1.0, label="still camera (median)")
        iou_ax = ex.twinx()
        for k, name in enumerate(paths):
            pr = [r for r in rows if int(r["faces"]) == n and r["path"] == name]
            if not pr:
                continue
            color = "C%d" % k
            x = [int(r["frame"]) for r in pr]
            ax.plot(x, [float(r["auto_ms"]) for r in pr], color=color, lw=1.2, label=name + ": reprojected, re-sliced by error")
            ax.plot(x, [float(r["every_ms"]) for r in pr], color=color, lw=0.8, ls="--", label=name + ": re-sliced every frame")
            rx = [int(r["frame"]) for r in pr if int(r["reslices"]) > 0]
            ax.plot(rx, [float(r["auto_ms"]) for r in pr if int(r["reslices"]) > 0], "o", color=color, ms=3)
            ex.plot(x, [float(r["sil_mean_px"]) for r in pr], color=color, lw=1.2, label=name + ": silhouette mean, px")
            iou_ax.plot(x, [float(r["iou"]) for r in pr], color=color, lw=0.8, ls=":", label=name + ": coverage IoU")
        ax.set_yscale("log")
        ax.set_xlabel("frame along the path")
        ax.set_ylabel("frame, ms (wall, log; dots: re-slices)")
        ax.set_title("%s, %d faces: frame time" % (title, n), fontsize=9)
        ax.grid(True, alpha=0.3, which="both")
        if col == 0:
            ax.legend(fontsize=5.5, ncol=2, loc="center right")
        ex.set_xlabel("frame along the path")
        ex.set_ylabel("silhouette mean, px (solid)")
        ex.set_ylim(bottom=0)
        iou_ax.set_ylabel("coverage IoU (dotted)")
        iou_ax.set_ylim(0.9, 1.0)
        ex.set_title("%d faces: error against re-slicing every frame" % n, fontsize=9)
        ex.grid(True, alpha=0.3)
        if col == 0:
            h1, l1 = ex.get_legend_handles_labels()
            h2, l2 = iou_ax.get_legend_handles_labels()
            ex.legend(h1 + h2, l1 + l2, fontsize=5.5, ncol=2, loc="lower right")
    fig.tight_layout()
    fig.savefig(out)
    print("wrote", out)


def plot_layercount(path, out, title):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    models = sorted({r["model"] for r in rows}, key=lambda m: [r["model"] for r in rows].index(m))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    for i, m in enumerate(models):
        color = "C%d" % i
        eq = [r for r in rows if r["model"] == m and "(" not in r["layout"]]
        x = [int(r["layers"]) for r in eq]
        a1.plot(x, [float(r["relative"]) for r in eq], "o-", color=color, label=m)
        a2.plot(x, [float(r["iou_mean"]) for r in eq], "o-", color=color, label=m)
        for r in rows:
            if r["model"] == m and "(" in r["layout"]:
                a1.plot(int(r["layers"]), float(r["relative"]), "s", color=color, mfc="none")
                a1.annotate(r["layout"], (int(r["layers"]), float(r["relative"])), fontsize=7, color=color,
                            xytext=(4, 4), textcoords="offset points")
    a1.set_xlabel("layers (equal spacing; squares: the paper's layouts)")
    a1.set_ylabel("colour difference / the wind's motion")
    a1.set_ylim(bottom=0)
    a2.set_xlabel("layers")
    a2.set_ylabel("coverage IoU (mean over frames)")
    for a in (a1, a2):
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    fig.suptitle(title + ": against 16 layers, the same wind", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=90)


def main():
    if len(sys.argv) >= 4 and sys.argv[1] == "--layercount":
        plot_layercount(sys.argv[2], sys.argv[3], sys.argv[4] if len(sys.argv) > 4 else "canopy-bench layercount")
        return
    if len(sys.argv) >= 4 and sys.argv[1] == "--camera":
        plot_camera(sys.argv[2], sys.argv[3], sys.argv[4] if len(sys.argv) > 4 else "canopy-bench camera")
        return
    if len(sys.argv) >= 4 and sys.argv[1] == "--pervertex":
        plot_pervertex(sys.argv[2], sys.argv[3], sys.argv[4] if len(sys.argv) > 4 else "canopy-bench pervertex")
        return
    if len(sys.argv) < 3:
        print(__doc__)
        sys.exit(2)
    folder, prefix = sys.argv[1], sys.argv[2]
    title = sys.argv[3] if len(sys.argv) > 3 else "canopy-bench table1 --series"
    for name, (xlabel, logx) in SERIES.items():
        with open("%s/series_%s.csv" % (folder, name)) as f:
            rows = list(csv.DictReader(f))
        x = [float(r["x"]) for r in rows]
        med = [float(r["median_ms"]) for r in rows]
        p95 = [float(r["p95_ms"]) for r in rows]
        fig, ax = plt.subplots(figsize=(5.2, 3.4), dpi=100)
        ax.plot(x, med, marker="o", label="median")
        ax.fill_between(x, med, p95, alpha=0.25, label="to p95")
        for xi, yi, r in zip(x, med, rows):
            ax.annotate(r["label"], (xi, yi), textcoords="offset points", xytext=(0, 6), ha="center", fontsize=7)
        if logx:
            ax.set_xscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("whole frame, ms (wall)")
        ax.set_ylim(bottom=0)
        ax.set_title("%s: frame vs %s" % (title, name), fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        out = "%s_%s.png" % (prefix, name)
        fig.savefig(out)
        print("wrote", out)


if __name__ == "__main__":
    main()
