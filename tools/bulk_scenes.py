#!/usr/bin/python3
"""The bulk Lennard-Jones example scenes of docs/topology.md (issue #26): one liquid on the Bolza
surface (genus 2) and its flat and spherical controls at the same density and number of bodies.

    /usr/bin/python3 tools/bulk_scenes.py [--bodies 400] [--density 0.6] [--kT 1.0] [--seed 26]
        [--out examples/scenes] [--run build/src/sesi --work sesi-out/bulk]

Writes three scenes of N bodies of unit mass, Lennard-Jones (epsilon = sigma = 1, cutoff 2.5):
  bulk-lj-bolza.toml   H^2 of radius R, genus 2 (area 4 pi (g - 1) R^2 = 4 pi R^2, Gauss-Bonnet)
  bulk-lj-sphere.toml  S^2 of the same radius R (area 4 pi R^2: the same density, curvature +1/R^2)
  bulk-lj-flat.toml    E^2 in a square periodic box of side L = (N / density)^(1/2)
with R = (N / (4 pi density))^(1/2). Positions by random sequential addition (uniform in the area
measure of each space, a candidate kept when its minimum-image geodesic distance to every kept body is
at least 1 sigma, where the pair energy is 0), velocities Maxwell at kT in the tangent plane,
rescaled so that the kinetic energy is exactly N kT (two degrees of freedom per body; on the box the
mean velocity is removed first). Numbers carry 17 significant digits, so the scenes are exact to the bit.
With --run, each scene is then run by that sesi program (`sesi run SCENE --out WORK/STEM`) and a
markdown table of its summary.json (energy error, run time) is printed (docs/topology.md).

The module also holds the regular 4g-gon of a compact hyperbolic surface (Polygon), which
tools/topology_figure.py draws: Sausset and Tarjus, J. Phys. A 40, 12873 (2007), section 3.
"""
import argparse
import json
import math
import pathlib
import random
import subprocess

import numpy as np

LJ_CUTOFF = 2.5
MIN_SEPARATION = 1.0  # sigma: where the Lennard-Jones energy 4 (r^-12 - r^-6) changes sign


def boost(direction, distance):
    """The Lorentz boost of the hyperboloid (x1, x2, x0), time-like last, that translates the origin
    (0, 0, 1) by `distance` (radius 1) along the unit vector `direction` of its tangent plane."""
    u = np.asarray(direction, dtype=float)
    m = np.eye(3)
    m[:2, :2] += (math.cosh(distance) - 1) * np.outer(u, u)
    m[:2, 2] = math.sinh(distance) * u
    m[2, :2] = math.sinh(distance) * u
    m[2, 2] = math.cosh(distance)
    return m


def lorentz(a, b):
    """<a, b>_L = a1 b1 + a2 b2 - a0 b0 (time-like coordinate last), over the last axis."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] - a[..., 2] * b[..., 2]


class Polygon:
    """The fundamental domain D of the genus-g surface on H^2 of radius 1: the regular 4g-gon centred
    at the origin with interior angles pi / (2 g), side k's midpoint in direction 2 pi k / (4 g), side
    k paired with side k + 2g (Sausset and Tarjus 2007, sec. 3; the convention of
    include/sesi/topologies/hyperbolic_surface.hpp). For a regular n-gon with interior angle alpha,
    cosh(inradius) = cos(pi/n) / sin(alpha/2) and cosh(circumradius) = cot(pi/n) cot(alpha/2)
    (Beardon, The Geometry of Discrete Groups, Thm 7.16.2); with n = 4g, alpha/2 = pi/n."""

    def __init__(self, genus):
        if genus < 2:
            raise ValueError(f"genus must be >= 2, not {genus}")
        self.genus = genus
        self.sides = n = 4 * genus
        cot = 1 / math.tan(math.pi / n)
        self.inradius = math.acosh(cot)
        self.circumradius = math.acosh(cot * cot)
        self.area = 4 * math.pi * (genus - 1)  # Gauss-Bonnet: (n - 2) pi - n alpha
        # generator(k): the translation by twice the inradius along the axis through side k's
        # midpoint; it maps D onto the tile across side k and side k + 2g onto side k.
        self.generators = [boost((math.cos(self.angle(k)), math.sin(self.angle(k))), 2 * self.inradius)
                           for k in range(n)]
        # Vertex j lies between sides j and j + 1, in direction 2 pi j / n + pi / n.
        rc = self.circumradius
        self.vertices = [np.array([math.sinh(rc) * math.cos(self.angle(j) + math.pi / n),
                                   math.sinh(rc) * math.sin(self.angle(j) + math.pi / n), math.cosh(rc)])
                         for j in range(n)]
        # Outward space-like normals: y is on D's side of side k iff <y, n_k>_L <= 0 (the bisector of
        # the origin and its image under generator(k)).
        origin = np.array([0.0, 0.0, 1.0])
        self.normals = np.array([(g @ origin - origin) / math.sqrt(2 * (math.cosh(2 * self.inradius) - 1))
                                 for g in self.generators])
        self.relation, self.images = self._walk_vertices()

    def angle(self, k):
        return 2 * math.pi * k / self.sides

    def inverse(self, k):
        return (k + self.sides // 2) % self.sides

    def _walk_vertices(self):
        """Every tile sharing a vertex with D, identity first: around vertex j, cross side j, then in
        each new tile the other side at the same vertex, 4g tiles in all. generator(s) maps vertex
        s + 2g - 1 onto vertex s and vertex s + 2g onto vertex s - 1 (it is a translation: it keeps
        the sides of its axis). The crossed letters around vertex 0 give the group relation."""
        n, images, centres, relation = self.sides, [np.eye(3)], [np.array([0.0, 0.0, 1.0])], None
        for j in range(n):
            m, side, vertex, letters, size = np.eye(3), j, j, [], 1.0
            for _ in range(n):
                m = m @ self.generators[side]
                size *= np.abs(self.generators[side]).max() * 3
                letters.append(side)
                came = self.inverse(side)
                vertex = (came - 1) % n if vertex == side else came  # the same point, in the new tile's labels
                side = (vertex + 1) % n if vertex == came else vertex  # the other side at that vertex
                # Tiles are told apart by their centres (the group acts freely), which lie at least
                # 2 inradius apart; the last product is the identity up to rounding.
                c = m[:, 2]
                if not any(-lorentz(c, other) < math.cosh(self.inradius) for other in centres):
                    images.append(m)
                    centres.append(c)
            # The product of 4g matrices is the identity to about eps times the product of their norms.
            assert np.abs(m - np.eye(3)).max() < 1e-13 * size, "the walk around a vertex must close"
            if j == 0:
                relation = letters
        return relation, images

    def outside(self, y):
        """Largest <y, n_k>_L over the sides: <= 0 inside D (a point on a side is inside)."""
        return float(np.max(self.normals @ (y * np.array([1.0, 1.0, -1.0]))))

    def distance(self, x, y):
        """Minimum-image geodesic distance (radius 1) between points of D, over the tiles sharing a
        vertex with D: the nearest image of y for any distance below the surface's largest cutoff."""
        ys = np.einsum("kab,b->ka", np.array(self.images), y)
        return math.acosh(max(1.0, float(np.min(-lorentz(ys, x)))))

    def uniform_point(self, rng):
        """A point uniform in D's area: uniform in the geodesic disc of the circumradius (the area
        element is sinh(rho) drho dphi, so cosh(rho) - 1 is uniform), kept when inside D."""
        while True:
            c = 1 + rng.random() * (math.cosh(self.circumradius) - 1)
            rho, phi = math.acosh(c), 2 * math.pi * rng.random()
            y = np.array([math.sinh(rho) * math.cos(phi), math.sinh(rho) * math.sin(phi), c])
            if self.outside(y) <= 0:
                return y


def random_sequential(n, candidate, too_close, rng, tries=200000):
    points = []
    for _ in range(tries):
        if len(points) == n:
            return points
        y = candidate(rng)
        if not any(too_close(y, p) for p in points):
            points.append(y)
    raise SystemExit(f"bulk_scenes.py: could not place {n} bodies at separation {MIN_SEPARATION} in {tries} tries")


def maxwell(tangents, kT, rng):
    """Velocities a e1 + b e2 with a, b normal of variance kT (unit masses), per tangent frame."""
    return [rng.gauss(0, math.sqrt(kT)) * e1 + rng.gauss(0, math.sqrt(kT)) * e2 for e1, e2 in tangents]


def rescale(velocities, kT, metric):
    """Scale so the kinetic energy sum v.v / 2 (in the space's metric) is N kT exactly."""
    kinetic = sum(metric(v, v) for v in velocities) / 2
    s = math.sqrt(len(velocities) * kT / kinetic)
    return [s * v for v in velocities]


def fmt(values):
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


def scene_text(title, name, space_lines, points, velocities, method, dt, t_end, output_every):
    lines = [f"# {title}", "# Written by tools/bulk_scenes.py (docs/topology.md); do not edit by hand.",
             f'name = "{name}"', "", "[space]", *space_lines, ""]
    for x, v in zip(points, velocities):
        lines += ["[[bodies]]", "mass = 1.0", f"x = {fmt(x)}", f"v = {fmt(v)}"]
    lines += ["", "[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0",
              f"cutoff = {LJ_CUTOFF!r}", "", "[integrator]", f'method = "{method}"', f"dt = {dt!r}",
              f"t_end = {t_end!r}", f"output_every = {output_every}", ""]
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bodies", type=int, default=400)
    ap.add_argument("--density", type=float, default=0.6)
    ap.add_argument("--kT", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=26)
    ap.add_argument("--method", default="sesi4")
    ap.add_argument("--dt", type=float, default=0.005)
    ap.add_argument("--t-end", type=float, default=10.0)
    ap.add_argument("--output-every", type=int, default=100)
    ap.add_argument("--out", default="examples/scenes")
    ap.add_argument("--run", metavar="SESI", help="run each scene with this sesi program and print a table")
    ap.add_argument("--work", default="sesi-out/bulk", help="where --run writes its output directories")
    a = ap.parse_args()
    if a.bodies < 2 or not a.density > 0 or not a.kT > 0:
        ap.error("need --bodies >= 2, --density > 0 and --kT > 0")
    radius = math.sqrt(a.bodies / (4 * math.pi * a.density))
    box = math.sqrt(a.bodies / a.density)
    common = (a.method, a.dt, a.t_end, a.output_every)
    what = f"{a.bodies} Lennard-Jones bodies at density {a.density!r} (bodies per sigma^2), kT = {a.kT!r}"
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)

    # H^2 genus 2 (Bolza): points R y with y in D on the unit hyperboloid; the tangent frame at y is
    # the boost taking the origin to y applied to the origin's (1, 0, 0) and (0, 1, 0).
    rng = random.Random(a.seed)
    bolza = Polygon(2)
    d_min = MIN_SEPARATION / radius
    ys = random_sequential(a.bodies, bolza.uniform_point, lambda y, p: bolza.distance(y, p) < d_min, rng)
    frames = []
    for y in ys:
        rho = math.acosh(y[2])
        u = y[:2] / np.linalg.norm(y[:2]) if rho > 0 else np.array([1.0, 0.0])
        b = boost(u, rho)
        frames.append((b[:, 0], b[:, 1]))
    vs = rescale(maxwell(frames, a.kT, rng), a.kT, lambda v, w: float(lorentz(v, w)))
    (out / "bulk-lj-bolza.toml").write_text(scene_text(
        f"{what} on the Bolza surface: H^2 of radius R = {radius:.6g}, genus 2 (docs/topology.md)", "bulk-lj-bolza",
        ['kind = "hyperbolic"', "dim = 2", f"radius = {radius!r}", "genus = 2"],
        [radius * y for y in ys], vs, *common))

    # S^2 of the same radius: uniform points (normalised Gaussian vectors).
    rng = random.Random(a.seed)

    def on_sphere(r):
        while True:
            v = np.array([r.gauss(0, 1) for _ in range(3)])
            if np.linalg.norm(v) > 1e-3:
                return v / np.linalg.norm(v)

    ss = random_sequential(a.bodies, on_sphere,
                           lambda y, p: math.acos(max(-1.0, min(1.0, float(y @ p)))) < d_min, rng)
    frames = []
    for s in ss:
        e1 = np.cross(s, [0.0, 0.0, 1.0] if abs(s[2]) < 0.9 else [1.0, 0.0, 0.0])
        e1 /= np.linalg.norm(e1)
        frames.append((e1, np.cross(s, e1)))
    vs = rescale(maxwell(frames, a.kT, rng), a.kT, lambda v, w: float(v @ w))
    (out / "bulk-lj-sphere.toml").write_text(scene_text(
        f"{what} on S^2 of radius R = {radius:.6g}: the spherical control of bulk-lj-bolza.toml", "bulk-lj-sphere",
        ['kind = "sphere"', "dim = 2", f"radius = {radius!r}"], [radius * s for s in ss], vs, *common))

    # E^2 box [0, L)^2, minimum image by nearest integer shifts (Allen and Tildesley, sec. 1.5.2).
    rng = random.Random(a.seed)

    def in_box(r):
        return np.array([r.random() * box, r.random() * box])

    def box_close(y, p):
        d = y - p
        d -= box * np.round(d / box)
        return float(np.hypot(d[0], d[1])) < MIN_SEPARATION

    fs = random_sequential(a.bodies, in_box, box_close, rng)
    frames = [(np.array([1.0, 0.0]), np.array([0.0, 1.0]))] * a.bodies
    vs = maxwell(frames, a.kT, rng)
    mean = sum(vs) / len(vs)
    vs = rescale([v - mean for v in vs], a.kT, lambda v, w: float(v @ w))
    (out / "bulk-lj-flat.toml").write_text(scene_text(
        f"{what} in an E^2 periodic box of side L = {box:.6g}: the flat control of bulk-lj-bolza.toml",
        "bulk-lj-flat", ['kind = "euclidean"', "dim = 2", f"box = {fmt([box, box])}"], fs, vs, *common))
    if a.run:
        run_table(a.run, [out / f"bulk-lj-{stem}.toml" for stem in ("bolza", "sphere", "flat")], pathlib.Path(a.work))


def run_table(sesi, scenes, work):
    """Runs each scene and prints one markdown row per run from its summary.json."""
    print("| scene | space | steps | max relative energy error | wall seconds | steps per second |")
    print("|---|---|---|---|---|---|")
    for scene in scenes:
        out = work / scene.stem
        done = subprocess.run([sesi, "run", str(scene), "--out", str(out), "-q"])
        if done.returncode != 0:
            raise SystemExit(f"bulk_scenes.py: `sesi run {scene}` failed with status {done.returncode}")
        s = json.loads((out / "summary.json").read_text())
        space = s["space"]
        what = {"hyperbolic": f"H^2, R = {space.get('radius', 0):.4g}, genus {space.get('genus')}",
                "sphere": f"S^2, R = {space.get('radius', 0):.4g}",
                "euclidean": f"E^2, box {' x '.join(f'{e:.4g}' for e in space.get('box', []))}"}[space["kind"]]
        print(f"| `{scene.name}` | {what} | {s['steps']} | {s['energy']['max_rel_error']:.2e} | "
              f"{s['wall_seconds']:.2f} | {s['steps'] / s['wall_seconds']:.0f} |")


if __name__ == "__main__":
    main()
