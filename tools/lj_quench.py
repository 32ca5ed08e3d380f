#!/usr/bin/python3
"""Quench a Lennard-Jones liquid on S^2 with a Langevin thermostat and draw g(r) at three
temperatures (issue #25, item 6; docs/observables.md, `make figures`).

    python3 tools/lj_quench.py --sesi build/src/sesi --out sesi-out/lj-quench \\
        [--figure docs/figures/lj-quench-g-r.png] [--bodies 600] [--plateau 20]

Writes OUT/lj-quench-s2.toml: N bodies of unit mass on the sphere that holds them at areal density
0.6 (bodies per sigma^2), on a Fibonacci spiral with Maxwell velocities at the first temperature,
Lennard-Jones (epsilon = sigma = 1, cutoff 2.5), method sesi2, dt = 0.005, and
[thermostat] kind = "langevin", gamma = 1, with the schedule kT = 2.0, 1.0, 0.45: three plateaus of
PLATEAU time units joined by ramps of 5. Runs it (`sesi run`), then `sesi analyze --from --to` over
the second half of each plateau (the first half lets the liquid follow the temperature; the
Langevin relaxation time 1/gamma = 1 is far shorter), keeps each window's rdf.csv as
OUT/rdf-kT<T>.csv, and draws the three g(r) with the kinetic temperature against time
(diagnostics.csv) into the figure. Needs matplotlib (Debian: python3-matplotlib).
"""
import argparse
import csv
import math
import pathlib
import random
import shutil
import subprocess
import sys

TEMPERATURES = [2.0, 1.0, 0.45]
RAMP = 5.0


def schedule(plateau):
    """[[t, kT], ...]: plateaus of length `plateau` joined by linear ramps; and each plateau's window."""
    knots, windows, t = [], [], 0.0
    for k, kT in enumerate(TEMPERATURES):
        if k > 0:
            t += RAMP
        knots.append([t, kT])
        windows.append((t + plateau / 2, t + plateau))
        t += plateau
        knots.append([t, kT])
    return knots, windows, t


def scene_text(bodies, plateau, seed):
    rng = random.Random(seed)
    density = 0.6
    radius = math.sqrt(bodies / (4 * math.pi * density))
    golden = math.pi * (3 - math.sqrt(5))
    knots, _, t_end = schedule(plateau)
    kT0 = TEMPERATURES[0]
    lines = [f"# {bodies} Lennard-Jones bodies on S^2 at density {density}, quenched kT = "
             + " -> ".join(f"{T:g}" for T in TEMPERATURES) + " by a Langevin thermostat (tools/lj_quench.py)",
             'name = "lj-quench-s2"', "", "[space]", 'kind = "sphere"', "dim = 2", f"radius = {radius!r}", ""]
    for k in range(bodies):
        z = 1 - 2 * (k + 0.5) / bodies
        rho = math.sqrt(1 - z * z)
        x = [radius * rho * math.cos(k * golden), radius * rho * math.sin(k * golden), radius * z]
        v = [rng.gauss(0, math.sqrt(kT0)) for _ in range(3)]
        dot = sum(xi * vi for xi, vi in zip(x, v)) / radius ** 2
        v = [vi - dot * xi for xi, vi in zip(x, v)]
        lines += ["[[bodies]]", "mass = 1.0", f"x = [{x[0]!r}, {x[1]!r}, {x[2]!r}]", f"v = [{v[0]!r}, {v[1]!r}, {v[2]!r}]"]
    lines += ["", "[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5", "",
              "[integrator]", 'method = "sesi2"', "dt = 0.005", f"t_end = {t_end!r}", "output_every = 100", "",
              "[thermostat]", 'kind = "langevin"', "gamma = 1.0", f"seed = {seed}",
              "temperature = [" + ", ".join(f"[{t!r}, {T!r}]" for t, T in knots) + "]", ""]
    return "\n".join(lines)


def read_columns(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: [float(r[k]) for r in rows[1:]] for k, name in enumerate(rows[0])}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sesi", required=True, help="the sesi program")
    ap.add_argument("--out", required=True, type=pathlib.Path, help="a directory for the scene, run and analysis")
    ap.add_argument("--figure", type=pathlib.Path, default=pathlib.Path("docs/figures/lj-quench-g-r.png"))
    ap.add_argument("--bodies", type=int, default=600)
    ap.add_argument("--plateau", type=float, default=20.0, help="time units at each temperature")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        sys.exit("lj_quench.py: matplotlib is missing (Debian: apt-get install python3-matplotlib)")

    a.out.mkdir(parents=True, exist_ok=True)
    scene = a.out / "lj-quench-s2.toml"
    scene.write_text(scene_text(a.bodies, a.plateau, a.seed))
    run = a.out / "run"
    subprocess.run([a.sesi, "run", str(scene), "--out", str(run), "--quiet"], check=True)
    _, windows, _ = schedule(a.plateau)
    curves = []
    for kT, (start, end) in zip(TEMPERATURES, windows):
        subprocess.run([a.sesi, "analyze", str(run), "--from", repr(start), "--to", repr(end), "--rdf-max", "5",
                        "--bins", "100", "--no-picture", "--quiet"], check=True)
        kept = a.out / f"rdf-kT{kT:g}.csv"
        shutil.copyfile(run / "rdf.csv", kept)
        curves.append((kT, start, end, read_columns(kept)))
    diagnostics = read_columns(run / "diagnostics.csv")

    figure, (left, right) = plt.subplots(1, 2, figsize=(12, 4.6), gridspec_kw={"width_ratios": [3, 2]})
    for (kT, start, end, g), color in zip(curves, ["C3", "C1", "C0"]):
        left.plot(g["r"], g["g"], color=color, linewidth=1.4, label=f"kT = {kT:g} (t in [{start:g}, {end:g}])")
    left.axhline(1.0, color="grey", linewidth=0.6, linestyle="--")
    left.set_xlabel("geodesic distance r (sigma)")
    left.set_ylabel("g(r)")
    left.set_title(f"{a.bodies} Lennard-Jones bodies on S^2 (density 0.6): g(r)")
    left.legend()
    if "kinetic_temperature" in diagnostics:
        right.plot(diagnostics["t"], diagnostics["kinetic_temperature"], color="C2", linewidth=0.8,
                   label="kinetic temperature 2K / 2N")
    if "temperature" in diagnostics:
        right.plot(diagnostics["t"], diagnostics["temperature"], color="black", linewidth=1.0, label="schedule kT")
    for _, start, end, _ in curves:
        right.axvspan(start, end, color="grey", alpha=0.15)
    right.set_xlabel("t")
    right.set_ylabel("kT")
    right.set_title("Langevin, gamma = 1; shaded: the g(r) windows")
    right.legend(loc="upper right", fontsize="small")
    figure.tight_layout()
    a.figure.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(a.figure, dpi=110)
    for kT, _, _, g in curves:
        peak = max(range(len(g["g"])), key=lambda k: g["g"][k])
        print(f"kT = {kT:g}: first peak g = {g['g'][peak]:.3f} at r = {g['r'][peak]:.3f}")
    print(f"wrote {a.figure}")


if __name__ == "__main__":
    main()
