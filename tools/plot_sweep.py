#!/usr/bin/env python3
"""Plot a two-key sweep of `sesi sweep` as maps (docs/sweeps.md).

    python3 tools/plot_sweep.py DIR [--x KEY] [--y KEY] [--twin KEY] [--out FILE]

Reads DIR/sweep.csv (and, for the twins, each run's DIR/runs/NNNN/summary.json). The grid is
the values of two varied keys: --x and --y, by default the first two varied columns. Left: the
largest relative energy error of each run (log10). Right, when a third varied key --twin (by
default the third column) takes two values: the separation of the twins at the end of the run,
the largest distance between the final embedding points x of the same body in the two runs
(log10), a Lyapunov-like measure of chaos. Runs that failed (exit status 3) are grey with a
cross. Writes DIR/sweep.png unless --out says otherwise. Needs matplotlib (Debian:
python3-matplotlib).
"""
import argparse
import csv
import json
import math
import pathlib
import sys

RESULT_COLUMNS = {"index", "status", "exit_status", "final_energy_error", "max_energy_error",
                  "max_rel_energy_error", "wall_seconds", "rank", "host", "message"}


def read_rows(directory):
    with open(directory / "sweep.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    varied = [name for name in rows[0] if name not in RESULT_COLUMNS] if rows else []
    return rows, varied


def final_points(directory, index, width):
    summary = json.loads((directory / "runs" / f"{index:0{width}d}" / "summary.json").read_text())
    return [body["x"] for body in summary["final_state"]["bodies"]]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dir", type=pathlib.Path)
    parser.add_argument("--x")
    parser.add_argument("--y")
    parser.add_argument("--twin")
    parser.add_argument("--out", type=pathlib.Path)
    parser.add_argument("--title", default="")
    args = parser.parse_args()

    rows, varied = read_rows(args.dir)
    if len(varied) < 2:
        sys.exit(f"plot_sweep.py: {args.dir}/sweep.csv varies {len(varied)} values; a map needs two")
    xkey, ykey = args.x or varied[0], args.y or varied[1]
    twin = args.twin or (varied[2] if len(varied) > 2 else None)
    width = max(4, len(str(len(rows) - 1)))
    if any(row["status"] == "pending" for row in rows):
        print(f"plot_sweep.py: warning: {args.dir} has runs not done yet; they are left blank", file=sys.stderr)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    xs = sorted({float(row[xkey]) for row in rows})
    ys = sorted({float(row[ykey]) for row in rows})
    energy = np.full((len(ys), len(xs)), np.nan)
    failed = np.zeros((len(ys), len(xs)), dtype=bool)
    runs = {}  # (i, j) -> [(twin value, index, status)]
    for row in rows:
        i, j = ys.index(float(row[ykey])), xs.index(float(row[xkey]))
        if row["status"] == "failed":
            failed[i, j] = True
        if row["status"] == "ok" and row["max_rel_energy_error"]:
            error = float(row["max_rel_energy_error"])
            energy[i, j] = max(energy[i, j], error) if not np.isnan(energy[i, j]) else error
        runs.setdefault((i, j), []).append((row.get(twin), int(row["index"]), row["status"]))

    separation = None
    if twin and len({row[twin] for row in rows}) == 2:
        separation = np.full((len(ys), len(xs)), np.nan)
        for (i, j), pair in runs.items():
            if len(pair) != 2 or any(status != "ok" for _, _, status in pair):
                continue
            a, b = (final_points(args.dir, index, width) for _, index, _ in pair)
            separation[i, j] = max(math.dist(p, q) for p, q in zip(a, b))

    panels = [("max relative energy error", energy)]
    if separation is not None:
        panels.append((f"separation of the twins at the end ({twin} nudged)", separation))
    fig, axes = plt.subplots(1, len(panels), figsize=(5.6 * len(panels), 4.6), squeeze=False)
    dx = (xs[-1] - xs[0]) / max(1, len(xs) - 1) or 1.0
    dy = (ys[-1] - ys[0]) / max(1, len(ys) - 1) or 1.0
    extent = [xs[0] - dx / 2, xs[-1] + dx / 2, ys[0] - dy / 2, ys[-1] + dy / 2]  # cells centred on the values
    for ax, (title, values) in zip(axes[0], panels):
        with np.errstate(divide="ignore"):
            shown = np.log10(np.where(values > 0, values, np.nan))
        image = ax.imshow(shown, origin="lower", aspect="auto", extent=extent, cmap="viridis", interpolation="nearest")
        fig.colorbar(image, ax=ax, label="log10")
        fy, fx = np.nonzero(failed)
        if len(fx):
            ax.scatter([xs[k] for k in fx], [ys[k] for k in fy], marker="x", s=14,
                       color="0.5", label="failed (exit 3)")
            ax.legend(loc="upper right", fontsize=8)
        ax.set_xlabel(xkey)
        ax.set_ylabel(ykey)
        ax.set_title(title, fontsize=10)
    if args.title:
        fig.suptitle(args.title)
    fig.tight_layout()
    out = args.out or args.dir / "sweep.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
