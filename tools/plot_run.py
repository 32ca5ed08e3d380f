#!/usr/bin/env python3
"""Plot the outputs of `sesi run` (docs/program.md).

    python3 tools/plot_run.py DIR [--body N] [--out FILE]

Left: the XY projection (embedding coordinates x1, x2) of body N's trajectory (trajectory.csv,
or trajectory.h5 with h5py), over the exact
curve when the run has one (exact.csv; the seed's scene: the six-petal orbit of
sesi::scenes::paper::Exact). Right: the energy error E(t) - E(0) against time. Writes
DIR/plot.png unless --out says otherwise. Needs matplotlib (Debian: python3-matplotlib).
"""
import argparse
import csv
import json
import pathlib
import sys


def read_columns(path):
    with open(path, newline="") as f:
        rows = csv.reader(f)
        header = next(rows)
        # (A surface run's b<k>_word columns are text, not numbers: not drawn.)
        columns = {name: [] for name in header if not name.endswith("_word")}
        for row in rows:
            for name, value in zip(header, row):
                if name in columns:
                    columns[name].append(float(value))
    return columns


def read_h5md_body(path, body):
    """t and body's embedding columns (b<body>_x<i>) of an H5MD trajectory (docs/scene-format.md)."""
    try:
        import h5py
    except ImportError:
        sys.exit("plot_run.py: reading trajectory.h5 needs h5py (Debian: apt-get install python3-h5py)")
    with h5py.File(path, "r") as f:
        position = f["particles/all/position"]
        columns = {"t": list(position["time"][:])}
        if body <= position["value"].shape[1]:
            x = position["value"][:, body - 1, :]
            for i in range(x.shape[1]):
                columns[f"b{body}_x{i + 1}"] = list(x[:, i])
    return columns


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dir", type=pathlib.Path, help="output directory of sesi run")
    parser.add_argument("--body", type=int, default=1, help="body to draw (1-based, default 1)")
    parser.add_argument("--out", type=pathlib.Path, help="image file (default DIR/plot.png)")
    args = parser.parse_args()

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("plot_run.py: matplotlib is missing (Debian: apt-get install python3-matplotlib)", file=sys.stderr)
        return 1

    summary = json.loads((args.dir / "summary.json").read_text())
    h5md = not (args.dir / "trajectory.csv").exists() and (args.dir / "trajectory.h5").exists()
    trajectory = (read_h5md_body(args.dir / "trajectory.h5", args.body) if h5md
                  else read_columns(args.dir / "trajectory.csv"))
    diagnostics = read_columns(args.dir / "diagnostics.csv")
    b = f"b{args.body}_"
    if b + "x1" not in trajectory:
        print(f"plot_run.py: no body {args.body} in {args.dir}", file=sys.stderr)
        return 1

    figure, (orbit, energy) = plt.subplots(1, 2, figsize=(12, 5.5))
    # E^1 has a single embedding coordinate: draw x1 against time then.
    if b + "x2" in trajectory:
        orbit.plot(trajectory[b + "x1"], trajectory[b + "x2"], color="C0", linewidth=1.5, alpha=0.6,
                   label=f"{summary['method']}, dt = {summary['dt']:g}")
        exact_path = args.dir / "exact.csv"
        if exact_path.exists():
            exact = read_columns(exact_path)
            orbit.plot(exact[b + "x1"], exact[b + "x2"], color="black", linewidth=0.7, label="exact")
        orbit.set_xlabel("x1")
        orbit.set_ylabel("x2")
        orbit.set_aspect("equal", adjustable="datalim")
    else:
        orbit.plot(trajectory["t"], trajectory[b + "x1"], color="C0", linewidth=0.8)
        orbit.set_xlabel("t")
        orbit.set_ylabel("x1")
    orbit.set_title(f"body {args.body}: XY projection")
    orbit.legend(loc="upper right", fontsize="small")

    energy.plot(diagnostics["t"], diagnostics["energy_error"], color="C3", linewidth=0.6)
    energy.axhline(0.0, color="0.5", linewidth=0.5)
    energy.set_xlabel("t")
    energy.set_ylabel("E(t) - E(0)")
    e = summary["energy"]
    energy.set_title(f"energy error (max |error| {e['max_abs_error']:.3g}, relative {e['max_rel_error']:.3g})"
                     if e["max_rel_error"] is not None else f"energy error (max |error| {e['max_abs_error']:.3g})")
    energy.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))

    space = summary["space"]
    status = "" if summary["complete"] else f"  [incomplete: {summary['stop_reason']}]"
    figure.suptitle(f"{summary['scene']}: {space['kind']} of dimension {space['dim']}, {summary['bodies']} bodies, "
                    f"{summary['steps']} steps to t = {summary['final_state']['t']:g}{status}")
    figure.tight_layout()
    out = args.out or args.dir / "plot.png"
    figure.savefig(out, dpi=120)
    # Into the run's manifest (sesi-manifest.txt, docs/scene-format.md): a picture sesi made, which
    # a run repeated into the directory replaces; pictures not listed there are the user's, and kept.
    manifest = pathlib.Path(out).parent / "sesi-manifest.txt"
    if manifest.is_file() and manifest.read_text().startswith("# sesi-manifest 1:"):
        if pathlib.Path(out).name not in manifest.read_text().splitlines()[1:]:
            with manifest.open("a") as f:
                f.write(pathlib.Path(out).name + "\n")
    print(f"plot_run.py: wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
