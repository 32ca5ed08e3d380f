#!/usr/bin/env python3
"""The pictures of docs/view.md, drawn by `sesi view`'s page itself in headless Chromium (issue #28).

    python3 tools/view_figures.py [--sesi build/src/sesi] [--chromium chromium] [--work sesi-out/view-figures]
        [--out docs/figures] [--only NAME,...]

Runs each scene with `sesi run`, writes its page with `sesi view` and takes an 800 x 600 screenshot
of it with URL parameters choosing the projection, frame, colours and trails (docs/view.md):
  view-s2-globe.png           the Lennard-Jones liquid on S^2 (examples/scenes/bulk-lj-sphere.toml), globe
  view-s2-stereographic.png   the same, stereographic from the south pole, coloured by speed
  view-s3-stereographic.png   free bodies on S^3 (geodesics: great circles), stereographic into R^3, trails
  view-h2-bolza.png           the liquid on the Bolza surface (bulk-lj-bolza.toml), Poincare disc, tiles
  view-h2-halfplane.png       free bodies on H^2 (geodesics), upper half-plane, trails
  view-h3-ball.png            free bodies on H^3 (geodesics), Poincare ball, trails
  view-e2-box.png             the liquid in a periodic box (bulk-lj-flat.toml), coloured by kinetic energy
  view-h2-hyperboloid.png     the free bodies on H^2 of view-h2-halfplane.png on the hyperboloid, trails
  view-e3-box.png             a Lennard-Jones liquid in a periodic box of E^3 (216 bodies), coloured by speed
  view-s5-stereographic.png   free bodies on S^5, stereographic into R^5, its first 3 coordinates (said so)
Scenes other than the examples are written here with fixed random numbers (seed 28).
"""
import argparse
import json
import math
import pathlib
import random
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent


def free_scene(name, kind, dim, count, seed, reach, speed, t_end, radius=1.0):
    """count free bodies (no potential: each follows a geodesic) on S^dim or H^dim of the given
    radius: uniform directions, hyperbolic distance up to reach R from the origin (H^n) or anywhere (S^n),
    random tangent velocities of the given speed."""
    rng = random.Random(seed)
    lines = [f'name = "{name}"', "[space]", f'kind = "{kind}"', f"dim = {dim}", f"radius = {radius!r}"]
    for _ in range(count):
        direction = [rng.gauss(0, 1) for _ in range(dim + 1)]
        if kind == "sphere":
            norm = math.sqrt(sum(c * c for c in direction))
            x = [radius * c / norm for c in direction]
            w = [rng.gauss(0, speed) for _ in range(dim + 1)]
            dot = sum(a * b for a, b in zip(x, w)) / radius ** 2
            v = [b - dot * a for a, b in zip(x, w)]
        else:
            u = direction[:dim]
            norm = math.sqrt(sum(c * c for c in u))
            d = reach * radius * rng.random() ** 0.5 + 1e-3
            x = [radius * math.sinh(d / radius) * c / norm for c in u] + [radius * math.cosh(d / radius)]
            w = [rng.gauss(0, speed) for _ in range(dim)]
            # tangent at x on the hyperboloid: v = (w, <w, x_space> / x_last)
            v = w + [sum(a * b for a, b in zip(w, x[:dim])) / x[dim]]
        lines += ["[[bodies]]", "mass = 1.0", f"x = [{', '.join(repr(c) for c in x)}]",
                  f"v = [{', '.join(repr(c) for c in v)}]"]
    lines += ["[integrator]", 'method = "sesi4"', "dt = 0.01", f"t_end = {t_end!r}", "output_every = 5"]
    return "\n".join(lines) + "\n"


def box_scene(name, side, density, seed, t_end):
    """side^3 Lennard-Jones bodies on a simple cubic lattice in a periodic box of E^3 at the given
    number density, with random velocities of zero total momentum (kT about 1)."""
    rng = random.Random(seed)
    edge = (side ** 3 / density) ** (1.0 / 3.0)
    spacing = edge / side
    points = [[(i + 0.5) * spacing, (j + 0.5) * spacing, (k + 0.5) * spacing]
              for i in range(side) for j in range(side) for k in range(side)]
    velocities = [[rng.gauss(0, 1) for _ in range(3)] for _ in points]
    mean = [sum(v[c] for v in velocities) / len(velocities) for c in range(3)]
    velocities = [[v[c] - mean[c] for c in range(3)] for v in velocities]
    lines = [f'name = "{name}"', "[space]", 'kind = "euclidean"', "dim = 3", f"box = [{edge!r}, {edge!r}, {edge!r}]"]
    for x, v in zip(points, velocities):
        lines += ["[[bodies]]", "mass = 1.0", f"x = [{', '.join(repr(c) for c in x)}]",
                  f"v = [{', '.join(repr(c) for c in v)}]"]
    lines += ["[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5",
              "[integrator]", 'method = "sesi2"', "dt = 0.005", f"t_end = {t_end!r}", "output_every = 10"]
    return "\n".join(lines) + "\n"


def chromium(program, isolate, what, url):
    """Headless Chromium on url (in an empty network namespace where `unshare -n` works); its stdout."""
    profile = tempfile.mkdtemp(prefix="chromium-")
    try:
        command = (["unshare", "-n"] if isolate else []) + [
            program, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync",
            "--enable-unsafe-swiftshader", f"--user-data-dir={profile}", "--force-device-scale-factor=1",
            "--hide-scrollbars", "--window-size=800,600", what, url]
        return subprocess.run(command, check=True, capture_output=True, text=True, timeout=120).stdout
    finally:
        shutil.rmtree(profile, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sesi", default=str(ROOT / "build" / "src" / "sesi"))
    ap.add_argument("--chromium", default=shutil.which("chromium") or shutil.which("chromium-browser") or "chromium")
    ap.add_argument("--work", default="sesi-out/view-figures")
    ap.add_argument("--out", default=str(ROOT / "docs" / "figures"))
    ap.add_argument("--only", default="")
    a = ap.parse_args()
    work = pathlib.Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    scenes = ROOT / "examples" / "scenes"
    written = {
        "s3-free": free_scene("s3-free", "sphere", 3, 120, 28, 0, 0.6, 4.0),
        "h2-free": free_scene("h2-free", "hyperbolic", 2, 60, 28, 2.5, 0.8, 3.0),
        "h3-free": free_scene("h3-free", "hyperbolic", 3, 150, 28, 3.0, 0.8, 3.0),
        "s5-free": free_scene("s5-free", "sphere", 5, 120, 28, 0, 0.6, 4.0),
        "e3-box": box_scene("e3-box", 6, 0.6, 28, 2.0),
    }
    # figure: (scene file or written scene, URL query)
    figures = {
        "s2-globe": ("bulk-lj-sphere", "frame=20&colour=speed"),
        "s2-stereographic": ("bulk-lj-sphere", "frame=20&projection=stereographic&colour=speed"),
        "s3-stereographic": ("s3-free", "frame=-1&trail=40"),
        "h2-bolza": ("bulk-lj-bolza", "frame=20&tiles=1"),
        "h2-halfplane": ("h2-free", "frame=-1&projection=halfplane&trail=60"),
        "h3-ball": ("h3-free", "frame=-1&trail=60"),
        "e2-box": ("bulk-lj-flat", "frame=20&colour=energy"),
        "h2-hyperboloid": ("h2-free", "frame=30&projection=hyperboloid&trail=30"),
        "e3-box": ("e3-box", "frame=-1&colour=speed"),
        "s5-stereographic": ("s5-free", "frame=-1&trail=40"),
    }
    only = set(filter(None, a.only.split(",")))
    isolate = subprocess.run(["unshare", "-n", "true"], capture_output=True).returncode == 0
    pages = {}
    for name, (source, query) in figures.items():
        if only and name not in only:
            continue
        if source not in pages:
            if source in written:
                scene = work / f"{source}.toml"
                scene.write_text(written[source])
            else:
                scene = scenes / f"{source}.toml"
            run = work / source
            subprocess.run([a.sesi, "run", str(scene), "--out", str(run), "--quiet"], check=True)
            subprocess.run([a.sesi, "view", str(run), "--quiet"], check=True)
            pages[source] = run / "view.html"
        if "frame=-1" in query:
            frames = sum(1 for _ in open(pages[source].parent / "trajectory.csv")) - 1
            query = query.replace("frame=-1", f"frame={frames - 1}")
        png = out / f"view-{name}.png"
        url = pages[source].resolve().as_uri() + "?" + query
        # the page's state first: a figure of a page that drew nothing (a banner) is an error
        dom = chromium(a.chromium, isolate, "--dump-dom", url)
        m = re.search(r'<script[^>]*id="sesi-state"[^>]*>(.*?)</script>', dom, re.S)
        state = json.loads(m.group(1)) if m else {}
        if not state.get("ready") or state.get("errors"):
            sys.exit(f"view_figures: {url} drew nothing: {state.get('messages')} {state.get('errors')}")
        chromium(a.chromium, isolate, f"--screenshot={png.resolve()}", url)
        print(f"{png}: {source} ?{query}")


if __name__ == "__main__":
    sys.exit(main())
