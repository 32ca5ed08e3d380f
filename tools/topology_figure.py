#!/usr/bin/python3
"""The compact hyperbolic surfaces of docs/topology.md (issue #26): the figure and the table.

    /usr/bin/python3 tools/topology_figure.py figure OUT.png [--sesi build/src/sesi] [--run DIR]
        [--scene examples/scenes/bulk-lj-bolza.toml] [--work sesi-out/topology] [--random 400] [--seed 1]
    /usr/bin/python3 tools/topology_figure.py table [--sesi build/src/sesi]

figure: the genus-2 fundamental domain (the regular octagon of the Bolza surface) in the Poincare
disc, its sides coloured and numbered by pair (side k and side k + 4, 1-based as in the trajectory's
words), the 48 tiles that share a vertex with it (faint: the images the minimum image searches), and
bodies drawn as discs of diameter sigma with their images in those tiles. The bodies are the last
frame of a run: DIR (`--run`, a `sesi run` output directory of a genus-2 scene), or the scene run
here with `--sesi` (into --work), else `--random` points uniform in the octagon (said in the title).

table: per genus g = 2..8 (radius 1): the polygon's inradius and circumradius, the area, the number of
tiles sharing a vertex with D, the largest generator entry, the shortest translation length among
those tiles' elements and their pairwise products (the systole when it is below the generators'
2 inradius), and with `--sesi` the largest allowed pair cutoff the program states (summary.json
"space" "max_cutoff", from a one-step run of a two-body scene), with the radius and number of bodies at
density 0.5 that a Lennard-Jones cutoff of 2.5 sigma needs. Needs NumPy and, for the figure,
matplotlib (Debian: python3-numpy, python3-matplotlib).
"""
import argparse
import csv
import json
import math
import pathlib
import random
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from bulk_scenes import Polygon, lorentz  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[1]
PAIR_COLOURS = ["tab:red", "tab:blue", "tab:green", "tab:orange", "tab:purple", "tab:brown", "tab:pink",
                "tab:olive"]


def disc(points):
    """Poincare disc coordinates of unit-hyperboloid points (x1, x2, x0): (x1, x2) / (1 + x0)."""
    p = np.atleast_2d(points)
    return p[:, :2] / (1 + p[:, 2:3])


def geodesic(a, b, samples=24):
    """Points of the geodesic segment from a to b on the unit hyperboloid."""
    d = math.acosh(max(1.0, -float(lorentz(a, b))))
    if d == 0:
        return np.array([a])
    t = np.linspace(0, 1, samples)[:, None]
    return (np.sinh((1 - t) * d) * a + np.sinh(t * d) * b) / math.sinh(d)


def polygon_outline(vertices):
    n = len(vertices)
    return np.vstack([disc(geodesic(vertices[j], vertices[(j + 1) % n])) for j in range(n)])


def hyperbolic_disc(y, r):
    """The Euclidean centre and radius in the Poincare disc of the hyperbolic circle of radius r
    (radius-1 units) around the unit-hyperboloid point y: its diameter along the ray through y runs
    from tanh((rho - r) / 2) to tanh((rho + r) / 2), rho = acosh(y0)."""
    rho = math.acosh(max(1.0, float(y[2])))
    u = y[:2] / np.linalg.norm(y[:2]) if np.linalg.norm(y[:2]) > 0 else np.array([1.0, 0.0])
    a, b = math.tanh((rho - r) / 2), math.tanh((rho + r) / 2)
    return (a + b) / 2 * u, (b - a) / 2


def last_frame(run):
    """Unit-hyperboloid points of the last trajectory row of a genus-g run, the radius and genus."""
    summary = json.loads((run / "summary.json").read_text())
    space = summary["space"]
    if space.get("kind") != "hyperbolic" or space.get("dim") != 2:
        sys.exit(f"topology_figure.py: {run} is not a run on H^2 (space {space})")
    radius = float(space["radius"])
    with open(run / "trajectory.csv") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    row = rows[-1]
    points = [np.array([float(row[f"b{b}_x{i}"]) for i in (1, 2, 3)]) / radius
              for b in range(1, int(summary["bodies"]) + 1)]
    source = pathlib.Path(summary.get("source", str(run))).resolve()
    shown = source.relative_to(REPO) if source.is_relative_to(REPO) else source
    return points, radius, int(space.get("genus", 2)), float(row["t"]), str(shown)


def figure(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle

    run = pathlib.Path(a.run) if a.run else None
    if a.sesi and not run:
        run = pathlib.Path(a.work)
        done = subprocess.run([a.sesi, "run", a.scene, "--out", str(run), "-q"])
        if done.returncode != 0:
            sys.exit(f"topology_figure.py: `sesi run {a.scene}` failed with status {done.returncode}")
    if run:
        points, radius, genus, t, source = last_frame(run)
        what = f"{len(points)} Lennard-Jones bodies at t = {t:g} ({source}), R = {radius:.4g} sigma"
    else:
        genus, radius = 2, math.sqrt(a.random / (4 * math.pi * 0.6))
        rng = random.Random(a.seed)
        polygon = Polygon(genus)
        points = [polygon.uniform_point(rng) for _ in range(a.random)]
        what = f"{a.random} random points uniform in the octagon (no run), R = {radius:.4g} sigma"
    if genus != 2:
        sys.exit(f"topology_figure.py: the figure draws genus 2 (the run has genus {genus})")
    polygon = Polygon(genus)
    n = polygon.sides

    fig, ax = plt.subplots(figsize=(8, 8))
    ax.add_patch(Circle((0, 0), 1, fill=False, lw=0.8, color="0.3"))
    for m in polygon.images[1:]:
        xy = polygon_outline([m @ v for v in polygon.vertices])
        ax.plot(xy[:, 0], xy[:, 1], color="0.75", lw=0.5)
    # Bodies: hyperbolic discs of diameter sigma (radius sigma / 2 in units of R), images faint.
    r = 0.5 / radius
    inside, images = [], []
    for y in points:
        c, s = hyperbolic_disc(y, r)
        inside.append(Circle(c, s))
        for m in polygon.images[1:]:
            c, s = hyperbolic_disc(m @ y, r)
            if s > 2.5e-3:  # smaller discs are below a pixel
                images.append(Circle(c, s))
    ax.add_collection(PatchCollection(images, facecolor="tab:blue", edgecolor="none", alpha=0.2))
    ax.add_collection(PatchCollection(inside, facecolor="tab:blue", edgecolor="navy", lw=0.3, alpha=0.85))
    # The octagon, side k coloured like its partner k + 2g, numbered 1-based at its midpoint.
    for k in range(n):
        v0, v1 = polygon.vertices[(k - 1) % n], polygon.vertices[k]
        xy = disc(geodesic(v0, v1))
        ax.plot(xy[:, 0], xy[:, 1], color=PAIR_COLOURS[k % (n // 2)], lw=2.5)
        mid = disc(np.array([math.sinh(polygon.inradius) * math.cos(polygon.angle(k)),
                             math.sinh(polygon.inradius) * math.sin(polygon.angle(k)),
                             math.cosh(polygon.inradius)]))[0]
        ax.text(*(mid * 1.1), str(k + 1), color=PAIR_COLOURS[k % (n // 2)], fontsize=13, fontweight="bold",
                ha="center", va="center",
                bbox=dict(boxstyle="round,pad=0.15", facecolor="white", edgecolor="none", alpha=0.8))
    pairs = ", ".join(f"{k + 1}~{k + 1 + n // 2}" for k in range(n // 2))
    ax.set_title(f"Bolza surface (genus 2): the octagon in the Poincare disc, sides paired {pairs}\n"
                 f"(a body leaving through side k re-enters through side k + 4); faint: the {len(polygon.images) - 1}"
                 f" tiles sharing a vertex\n{what}", fontsize=9.5)
    ax.set_xlim(-1.02, 1.02)
    ax.set_ylim(-1.02, 1.02)
    ax.set_aspect("equal")
    ax.axis("off")
    fig.tight_layout()
    fig.savefig(a.out, dpi=100)
    try:  # a 256-colour palette: the faint images' antialiasing makes a true-colour PNG 3x larger
        from PIL import Image
        Image.open(a.out).convert("RGB").quantize(256).save(a.out, optimize=True)
    except ImportError:
        pass
    print(f"wrote {a.out}: {what}")


def translation_length(m):
    """For a hyperbolic element of SO+(2,1), trace = 1 + 2 cosh(translation length)."""
    return math.acosh(max(1.0, (float(np.trace(m)) - 1) / 2))


def shortest_translation(polygon):
    """The least translation length among the tiles' elements and their pairwise products, the
    identity excluded (told apart by where it sends the origin: it moves it by 2 inradius at least)."""
    ms = np.array(polygon.images[1:])
    best = min(translation_length(m) for m in ms)
    for m in ms:
        products = np.einsum("ab,kbc->kac", m, ms)
        moved = products[:, 2, 2] > math.cosh(polygon.inradius)  # cosh of the origin's displacement
        traces = np.einsum("kaa->k", products[moved])
        best = min(best, math.acosh(max(1.0, (float(traces.min()) - 1) / 2)))
    return best


def program_max_cutoff(sesi, genus):
    """summary.json's max_cutoff for a two-body, one-step scene on the genus-g surface of radius 1."""
    scene = (f'name = "max-cutoff-g{genus}"\n[space]\nkind = "hyperbolic"\ndim = 2\nradius = 1.0\ngenus = {genus}\n'
             # (sinh 0.5, 0, cosh 0.5) and (0, sinh 0.5, cosh 0.5): off the chart's singular origin.
             "[[bodies]]\nmass = 1.0\nx = [0.5210953054937474, 0.0, 1.1276259652063807]\nv = [0.0, 0.1, 0.0]\n"
             "[[bodies]]\nmass = 1.0\nx = [0.0, 0.5210953054937474, 1.1276259652063807]\nv = [0.1, 0.0, 0.0]\n"
             "[integrator]\nmethod = \"sesi2\"\ndt = 0.01\nt_end = 0.01\n")
    with tempfile.TemporaryDirectory() as work:
        path = pathlib.Path(work) / "scene.toml"
        path.write_text(scene)
        done = subprocess.run([sesi, "run", str(path), "--out", str(pathlib.Path(work) / "out"), "-q"],
                              capture_output=True, text=True)
        if done.returncode != 0:
            sys.exit(f"topology_figure.py: sesi refused genus {genus}: {done.stderr.strip()}")
        return float(json.loads((pathlib.Path(work) / "out" / "summary.json").read_text())["space"]["max_cutoff"])


def table(a):
    head = ["g", "sides", "inradius", "circumradius", "area", "tiles", "largest generator entry",
            "shortest translation"]
    if a.sesi:
        head += ["max_cutoff (sesi)", "R for cutoff 2.5", "N at density 0.5"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for g in range(2, 9):
        p = Polygon(g)
        row = [str(g), str(p.sides), f"{p.inradius:.4f}", f"{p.circumradius:.4f}", f"{p.area:.4f}",
               str(len(p.images)), f"{math.cosh(2 * p.inradius):.4g}", f"{shortest_translation(p):.4f}"]
        if a.sesi:
            c = program_max_cutoff(a.sesi, g)
            r = 2.5 / c
            row += [f"{c:.4f}", f"{r:.3f}", f"{0.5 * p.area * r * r:.0f}"]
        print("| " + " | ".join(row) + " |")
    print("\nLengths in units of the radius R, areas in R^2 (tools/topology_figure.py table"
          + (" --sesi)" if a.sesi else ")"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    f = sub.add_parser("figure")
    f.add_argument("out")
    f.add_argument("--sesi", help="run --scene with this sesi program and draw its last frame")
    f.add_argument("--run", help="draw the last frame of this sesi output directory")
    f.add_argument("--scene", default=str(REPO / "examples" / "scenes" / "bulk-lj-bolza.toml"))
    f.add_argument("--work", default="sesi-out/topology")
    f.add_argument("--random", type=int, default=400)
    f.add_argument("--seed", type=int, default=1)
    t = sub.add_parser("table")
    t.add_argument("--sesi")
    a = ap.parse_args()
    figure(a) if a.command == "figure" else table(a)


if __name__ == "__main__":
    main()
