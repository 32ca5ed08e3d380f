#!/usr/bin/python3
"""Time per step against the number of bodies, from `sesi bench --scaling` (issue #11).

    /usr/bin/python3 tools/plot_scaling.py DIR [DIR ...] [--figure PNG] [--markdown]

Each DIR holds a scaling.csv. Plots seconds per step against N on log-log axes, one line per
(space, dimension, potential, method, threads), with dashed O(N) and O(N^2) guides through the
first point, and prints per series the log-log slopes and, at every N, the ratios to the
references of the same run (sesi on flat E^3, the plain flat cell-list loop, LAMMPS on the E^n box
at the same N and density with as many ranks as threads (issue #27; S^n rows and --box rows), and
for an H^n cluster away from the chart origin the same cluster at the origin).
"""
import argparse
import csv
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(directory):
    path = os.path.join(directory, "scaling.csv")
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    rows = list(csv.DictReader(lines))
    for r in rows:
        for key in ("n_bodies", "dim", "threads"):
            r[key] = int(r[key])
        for key in ("seconds_per_step", "pairs_per_step", "ns_per_pair", "peak_rss_mb"):
            r[key] = float(r[key])
        r["center_distance"] = float(r.get("center_distance") or 0)
        r["source"] = directory
    return rows


def label(r):
    if r["space"] == "flat-periodic":
        return "flat cell-list loop (3-D, 1 thread)" + r.get("tag", "")
    if r["space"] == "lammps":
        return f"LAMMPS E^{r['dim']} box ({r['threads']} ranks)" + r.get("tag", "")
    symbol = {"sphere": "S", "hyperbolic": "H", "euclidean": "E"}[r["space"]]
    far = f" centre {r['center_distance']:g} R away" if r["center_distance"] else ""
    topology = f" {r['topology']}" if r.get("topology") else ""
    return f"{symbol}^{r['dim']}{topology} {r['potential']} {r['method']} {r['threads']} thr{far}" + r.get("tag", "")


def series_of(rows):
    series = {}
    for r in rows:
        series.setdefault((r["source"], label(r)), []).append(r)
    for s in series.values():
        s.sort(key=lambda r: r["n_bodies"])
    return series


def slope(a, b):
    return math.log(b["seconds_per_step"] / a["seconds_per_step"]) / math.log(b["n_bodies"] / a["n_bodies"])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dirs", nargs="+")
    parser.add_argument("--figure", help="output PNG (default DIR/scaling.png of the first DIR)")
    parser.add_argument("--markdown", action="store_true", help="print the table as Markdown")
    args = parser.parse_args()
    rows = [r for d in args.dirs for r in read(d)]
    if len(args.dirs) > 1:  # name the sweep, e.g. scaling-h2 and scaling-h2-far
        for r in rows:
            r["tag"] = f" ({os.path.basename(os.path.normpath(r['source']))})"
    series = series_of(rows)

    fig, ax = plt.subplots(figsize=(7, 5))
    for (source, name), s in series.items():
        ax.loglog([r["n_bodies"] for r in s], [r["seconds_per_step"] for r in s], "o-", label=name)
    first = min(rows, key=lambda r: (r["n_bodies"], -r["seconds_per_step"]))
    n_max = max(r["n_bodies"] for r in rows)
    for power, style in ((1, "k--"), (2, "k:")):
        ns = [first["n_bodies"], n_max]
        ax.loglog(ns, [first["seconds_per_step"] * (n / ns[0]) ** power for n in ns], style, lw=0.8,
                  label=f"O(N^{power})" if power > 1 else "O(N)")
    ax.set_xlabel("bodies N")
    ax.set_ylabel("seconds per step")
    ax.set_title("sesi bench --scaling")
    ax.grid(True, which="both", lw=0.3)
    ax.legend(fontsize=7)
    out = args.figure or os.path.join(args.dirs[0], "scaling.png")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")

    print("\nlog-log slope of seconds per step against N:")
    for (source, name), s in series.items():
        if len(s) > 1:
            steps = ", ".join(f"{a['n_bodies']}-{b['n_bodies']}: {slope(a, b):.2f}" for a, b in zip(s, s[1:]))
            print(f"  {name}: {steps}; all {slope(s[0], s[-1]):.2f}")

    print()
    if args.markdown:
        print("| N | series | s/step | ns/pair | peak MB | / sesi E^3 | / flat cell list | / LAMMPS | far / origin |")
        print("|---|---|---|---|---|---|---|---|---|")
    for r in sorted(rows, key=lambda r: (r["source"], r["n_bodies"], label(r))):
        same = [q for q in rows if q["source"] == r["source"] and q["n_bodies"] == r["n_bodies"]]
        flat = [q for q in same if q["space"] == "flat-periodic"]
        e3 = [q for q in same if q["space"] == "euclidean" and q["dim"] == 3 and q["method"] == r["method"]
              and q["threads"] == r["threads"] and q is not r]
        ratio_e3 = f"{r['seconds_per_step'] / e3[0]['seconds_per_step']:.2f}" if e3 and r["space"] != "euclidean" else ""
        ratio_flat = (f"{r['seconds_per_step'] / flat[0]['seconds_per_step']:.2f}"
                      if flat and r["space"] not in ("flat-periodic", "lammps") else "")
        lammps = [q for q in same if q["space"] == "lammps" and q["dim"] == r["dim"] and q["threads"] == r["threads"]
                  and (r["space"] == "sphere" or r.get("topology") == "box") and r["space"] != "lammps"]
        ratio_lammps = f"{r['seconds_per_step'] / lammps[0]['seconds_per_step']:.2f}" if lammps else ""
        origin = [q for q in same if r["center_distance"] and q["space"] == r["space"] and q["dim"] == r["dim"]
                  and q["method"] == r["method"] and q["threads"] == r["threads"] and not q["center_distance"]]
        ratio_origin = f"{r['seconds_per_step'] / origin[0]['seconds_per_step']:.2f}" if origin else ""
        cells = [str(r["n_bodies"]), label(r), f"{r['seconds_per_step']:.4g}", f"{r['ns_per_pair']:.3g}",
                 f"{r['peak_rss_mb']:.0f}" if r["space"] != "lammps" else "", ratio_e3, ratio_flat, ratio_lammps, ratio_origin]
        print(("| " + " | ".join(cells) + " |") if args.markdown else "  " + "  ".join(cells))


if __name__ == "__main__":
    main()
