#!/usr/bin/python3
"""Work-precision plots, tables and the performance targets of `sesi bench` (issue #4).

    /usr/bin/python3 tools/plot_bench.py DIR [DIR ...] [--figures OUTDIR] [--markdown]

Each DIR holds a work_precision.csv written by `sesi bench --out DIR`. For each, writes
OUTDIR/<scene>-final-error.png and OUTDIR/<scene>-energy-error.png (log-log error against wall
time and against force evaluations), and prints the table of docs/benchmarks.md and the target
figures (ratios from the rows of one CSV, i.e. measured in the same run):
  - paper: at every max-energy-error level dopri5 reaches in [1e-10, 1e-4], the time of dopri5
    over the time of the fastest SESI method reaching that level (target >= 10); and the run
    time of implicit-midpoint over sesi2 at dt = 0.1 (the seed says about 100);
  - every scene: the best SESI chart method's time over the best embedding method's time at
    equal final error, over the error range both reach (target <= 2 on the Kepler scenes).
Frontiers are the lower envelopes (cost against error) of a family's runs, interpolated
linearly in log-log between runs.
"""
import argparse
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SESI = ["sesi2", "sesi4", "sesi4-suzuki", "sesi4-mclachlan", "sesi6", "sesi6-kahan-li", "sesi8",
        "sesi8-kahan-li"]
EMBEDDING = ["rattle", "geodesic2", "geodesic4", "geodesic6"]


def read(directory):
    path = os.path.join(directory, "work_precision.csv")
    notes, rows = [], []
    with open(path) as f:
        lines = []
        for line in f:
            if line.startswith("#"):
                notes.append(line[1:].strip())
            else:
                lines.append(line)
    for r in csv.DictReader(lines):
        for k in ("dt_or_tol", "wall_seconds", "final_error", "max_energy_error",
                  "max_momentum_drift"):
            r[k] = float(r[k])
        for k in ("steps", "force_evals", "order"):
            r[k] = int(r[k])
        rows.append(r)
    scene = os.path.basename(os.path.normpath(directory))
    for n in notes:
        if n.startswith("scene: "):
            scene = n.split()[1]
    return scene, notes, rows


def frontier(rows, err, cost):
    """Lower envelope: points (error, cost) sorted by cost, each more accurate than all cheaper."""
    pts = sorted((r[cost], r[err]) for r in rows if r[err] > 0)
    out, best = [], math.inf
    for c, e in pts:
        if e < best:
            out.append((e, c))
            best = e
    return out  # error descending, cost ascending


def cost_at(front, level):
    """Cost to reach error `level` on a frontier, log-log interpolated; None outside its range."""
    if not front or level > front[0][0]:
        return front[0][1] if front and level >= front[0][0] else None
    for (e0, c0), (e1, c1) in zip(front, front[1:]):
        if e1 <= level <= e0:
            if e0 == e1:
                return c1
            w = (math.log(e0) - math.log(level)) / (math.log(e0) - math.log(e1))
            return math.exp(math.log(c0) + w * (math.log(c1) - math.log(c0)))
    return None


def reach(rows, err, level):
    """Least wall time of a run with error <= level (no interpolation), or None."""
    ok = [r["wall_seconds"] for r in rows if r[err] <= level]
    return min(ok) if ok else None


def plot(scene, rows, outdir):
    methods = []
    for r in rows:
        if r["method"] not in methods:
            methods.append(r["method"])
    for err, label, name in (("final_error", "final error (largest geodesic distance)", "final-error"),
                             ("max_energy_error", "max |E(t) - E(0)|", "energy-error")):
        fig, axes = plt.subplots(1, 2, figsize=(13, 5.5))
        for ax, cost, xlabel in ((axes[0], "wall_seconds", "wall time [s] (min of repeats)"),
                                 (axes[1], "force_evals", "force evaluations")):
            for m in methods:
                pts = sorted((r[cost], r[err]) for r in rows if r["method"] == m and r[err] > 0)
                if not pts:
                    continue
                style = "-o" if m in SESI else ("--s" if m in EMBEDDING else ":^")
                ax.loglog([p[0] for p in pts], [p[1] for p in pts], style, ms=3.5, lw=1.2,
                          label=m)
            ax.set_xlabel(xlabel)
            ax.set_ylabel(label)
            ax.grid(True, which="both", alpha=0.3)
        axes[1].legend(fontsize=7, ncol=2, loc="lower left")
        fig.suptitle(f"sesi bench --scene {scene}: {label} against cost "
                     "(solid: SESI chart, dashed: embedding, dotted: other references)")
        fig.tight_layout()
        path = os.path.join(outdir, f"{scene}-{name}.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print(f"wrote {path}")


def fmt(x):
    return "—" if x is None else f"{x:.3g}"


def table(scene, rows):
    levels = [("final_error", 1e-4), ("final_error", 1e-8), ("max_energy_error", 1e-6),
              ("max_energy_error", 1e-10)]
    print(f"\n| {scene}: method | order | " + " | ".join(
        f"s to {'final' if e == 'final_error' else 'energy'} err {l:.0e}" for e, l in levels)
        + " | min evals/step |")
    print("|---|---|" + "---|" * len(levels) + "---|")
    seen = []
    for r in rows:
        if r["method"] in seen:
            continue
        seen.append(r["method"])
        mine = [x for x in rows if x["method"] == r["method"]]
        per_step = min(x["force_evals"] / max(x["steps"], 1) for x in mine)
        print(f"| {r['method']} | {r['order'] or '-'} | "
              + " | ".join(fmt(reach(mine, e, l)) for e, l in levels) + f" | {per_step:.3g} |")


def targets(scene, rows):
    fam = lambda names: [r for r in rows if r["method"] in names]
    sesi, emb = fam(SESI), fam(EMBEDDING)
    print(f"\n## targets, scene {scene}")
    dop = [r for r in rows if r["method"] == "dopri5" and 1e-10 <= r["max_energy_error"] <= 1e-4]
    if dop and sesi:
        front = frontier(sesi, "max_energy_error", "wall_seconds")
        worst = math.inf
        for r in sorted(dop, key=lambda r: -r["max_energy_error"]):
            c = cost_at(front, r["max_energy_error"])
            ratio = r["wall_seconds"] / c if c else None
            if ratio is not None:
                worst = min(worst, ratio)
            print(f"  dopri5 tol {r['dt_or_tol']:.1e}: max energy error {r['max_energy_error']:.2e}"
                  f" in {r['wall_seconds']:.3g} s; fastest SESI {fmt(c)} s; ratio {fmt(ratio)}")
        print(f"  TARGET (paper scene) dopri5/SESI >= 10 at every level in [1e-10, 1e-4]: worst ratio "
              f"{worst:.3g} -> {'MET' if worst >= 10 else 'MISSED'}")
    imr = [r for r in rows if r["method"] == "implicit-midpoint" and abs(r["dt_or_tol"] - 0.1) < 1e-12]
    s2 = [r for r in rows if r["method"] == "sesi2" and abs(r["dt_or_tol"] - 0.1) < 1e-12]
    if imr and s2:
        print(f"  implicit-midpoint / sesi2 at dt = 0.1: {imr[0]['wall_seconds']:.3g} s / "
              f"{s2[0]['wall_seconds']:.3g} s = {imr[0]['wall_seconds'] / s2[0]['wall_seconds']:.3g}"
              f" (force evaluations {imr[0]['force_evals']} / {s2[0]['force_evals']}; seed: ~100)")
    if sesi and emb:
        for cap in (math.inf, 1e-2):
            compare(sesi, emb, cap)


def compare(sesi, emb, cap):
    """Best SESI over best embedding time at equal final error, at errors <= cap."""
    if True:
        fs = frontier(sesi, "final_error", "wall_seconds")
        fe = frontier(emb, "final_error", "wall_seconds")
        lo = max(fs[-1][0], fe[-1][0])
        hi = min(fs[0][0], fe[0][0], cap)
        print(f"  final errors <= {cap:g}:" if cap < math.inf else "  all final errors:")
        ratios = []
        if lo < hi:
            n = 24
            for k in range(n + 1):
                level = math.exp(math.log(hi) + (math.log(lo) - math.log(hi)) * k / n)
                cs, ce = cost_at(fs, level), cost_at(fe, level)
                if cs and ce:
                    ratios.append((level, cs / ce))
        if ratios:
            worst = max(ratios, key=lambda x: x[1])
            best = min(ratios, key=lambda x: x[1])
            print(f"  best SESI / best embedding time at equal final error, over [{lo:.1e}, {hi:.1e}]:"
                  f" worst {worst[1]:.3g} (at {worst[0]:.1e}), best {best[1]:.3g} (at {best[0]:.1e})")
            for level, ratio in ratios[:: max(1, len(ratios) // 6)]:
                print(f"    at final error {level:.1e}: {ratio:.3g}")
            print(f"  TARGET (Kepler scenes) SESI/embedding <= 2: "
                  f"{'MET' if worst[1] <= 2 else 'MISSED'} (worst {worst[1]:.3g})")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--figures", default=None, help="where the PNGs go (default: each DIR)")
    ap.add_argument("--markdown", action="store_true", help="print the tables")
    a = ap.parse_args()
    for d in a.dirs:
        scene, notes, rows = read(d)
        outdir = a.figures or d
        os.makedirs(outdir, exist_ok=True)
        print(f"# {d}: " + "; ".join(notes))
        plot(scene, rows, outdir)
        if a.markdown:
            table(scene, rows)
        targets(scene, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
