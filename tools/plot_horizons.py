#!/usr/bin/python3
"""Cost against run length from `sesi bench --horizons` (issue #15).

    /usr/bin/python3 tools/plot_horizons.py DIR/horizons.csv --figure docs/figures/horizons-paper.png
        [--markdown]

Reads horizons.csv (one row per method, horizon and level: the least wall time of any run of the
method's sweep at that horizon reaching max energy error <= level) and draws wall seconds
against the horizon, log-log, one panel per level, one line per method: the methods of `sesi run`
(sesi*, geodesic*) solid, rk78 and dopri5 dashed, any other method dotted; a level a method does not reach at a
horizon leaves a gap. With --markdown, prints the table of docs/benchmarks.md: per horizon and
level the fastest sesi method against rk78's and dopri5's fastest, with the ratios (their time
over the sesi method's; '-' where the reference reached no run at that level).
"""
import argparse
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

REFERENCES = ("rk78", "dopri5")


def read(path):
    notes, lines = [], []
    with open(path) as f:
        for line in f:
            (notes if line.startswith("#") else lines).append(line)
    rows = []
    for r in csv.DictReader(lines):
        for k in ("horizon", "level", "dt_or_tol", "wall_seconds", "max_energy_error", "best_error"):
            r[k] = float(r[k])
        r["order"] = int(r["order"])
        r["reached"] = r["reached"] == "yes"
        rows.append(r)
    scene = "?"
    for n in notes:
        if n.startswith("# scene: "):
            scene = n.split()[2]
    return scene, rows


def is_sesi(method):
    """A method of `sesi run`: the chart methods and the geodesic (embedding) ones."""
    return method.startswith(("sesi", "geodesic"))


def style(method):
    if is_sesi(method):
        return "-"
    return "--" if method in REFERENCES else ":"


def plot(scene, rows, figure):
    levels = sorted({r["level"] for r in rows}, reverse=True)
    methods = list(dict.fromkeys(r["method"] for r in rows))
    cols = min(3, len(levels))
    nrows = math.ceil(len(levels) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.6 * cols, 3.8 * nrows), squeeze=False,
                             sharex=True, sharey=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, level in enumerate(levels):
        ax = axes[i // cols][i % cols]
        for j, m in enumerate(methods):
            pts = sorted((r["horizon"], r["wall_seconds"]) for r in rows
                         if r["method"] == m and r["level"] == level)
            # NaN for unreached points: matplotlib leaves a gap there.
            xs = [p[0] for p in pts]
            ys = [p[1] if math.isfinite(p[1]) else float("nan") for p in pts]
            if not any(math.isfinite(y) for y in ys):
                continue
            ax.plot(xs, ys, style(m), marker="o", markersize=3, color=colours[j % len(colours)],
                    linewidth=2.0 if m in REFERENCES else 1.3, label=m)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"max energy error <= {level:g}")
        ax.grid(True, which="both", alpha=0.3)
        if i % cols == 0:
            ax.set_ylabel("wall seconds (fastest run)")
        if i // cols == nrows - 1:
            ax.set_xlabel("horizon T")
    for i in range(len(levels), nrows * cols):
        axes[i // cols][i % cols].set_visible(False)
    handles, labels = {}, {}
    for ax in axes.flat:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    fig.legend(list(handles.values()), list(handles.keys()), loc="lower center",
               ncol=min(len(handles), 5), fontsize=8, frameon=False)
    fig.suptitle(f"{scene}: least wall time to a max energy error level, against the horizon")
    fig.tight_layout(rect=(0, 0.04 + 0.025 * math.ceil(len(handles) / 5), 1, 0.97))
    fig.savefig(figure, dpi=110)
    plt.close(fig)


def markdown(scene, rows):
    horizons = sorted({r["horizon"] for r in rows})
    levels = sorted({r["level"] for r in rows}, reverse=True)
    print(f"| {scene}: T | level | fastest sesi method (setting) | s | rk78 s | rk78 / sesi | "
          "dopri5 s | dopri5 / sesi |")
    print("|---|---|---|---|---|---|---|---|")
    for h in horizons:
        for lev in levels:
            cell = [r for r in rows if r["horizon"] == h and r["level"] == lev]
            sesi = [r for r in cell if is_sesi(r["method"]) and r["reached"]]
            best = min(sesi, key=lambda r: r["wall_seconds"]) if sesi else None
            out = [f"{h:g}", f"{lev:g}"]
            if best:
                kind = "tol" if best["method"] in ("dopri5", "rk78", "bulirsch-stoer") else "dt"
                out += [f"{best['method']} ({kind} {best['dt_or_tol']:.3g})", f"{best['wall_seconds']:.3g}"]
            else:
                out += ["none reached", "—"]
            for ref in REFERENCES:
                r = next((r for r in cell if r["method"] == ref), None)
                if r is None:
                    out += ["not run", ""]
                elif not r["reached"]:
                    out += [f"— (best {r['best_error']:.1e})", ""]
                else:
                    ratio = f"{r['wall_seconds'] / best['wall_seconds']:.2f}" if best else ""
                    out += [f"{r['wall_seconds']:.3g}", ratio]
            print("| " + " | ".join(out) + " |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", help="horizons.csv of sesi bench --horizons")
    ap.add_argument("--figure", help="PNG to write")
    ap.add_argument("--markdown", action="store_true", help="print the ratio table")
    a = ap.parse_args()
    scene, rows = read(a.csv)
    if not rows:
        print(f"{a.csv}: no rows", file=sys.stderr)
        return 1
    if a.figure:
        plot(scene, rows, a.figure)
        print(f"wrote {a.figure}", file=sys.stderr)
    if a.markdown:
        markdown(scene, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
