#!/usr/bin/python3
"""A many-body scene file: Lennard-Jones bodies on S^2 on a Fibonacci lattice (issue #11).

    python3 tools/lattice_scene.py N OUT.toml [--density 0.5] [--speed 1] [--seed 1]
        [--method sesi2] [--dt 0.002] [--t-end 0.2] [--output-every 100]

N bodies of unit mass on the sphere holding them at the given areal density (bodies per
sigma^2; radius sqrt(N / (4 pi density))), equal-area spiral points a golden angle apart, with
random tangent velocities (normal components of deviation --speed, the normal part removed),
Lennard-Jones with epsilon = sigma = 1 and cutoff 2.5. The same bodies as `sesi bench --scaling`
on S^2 (docs/benchmarks.md), up to the velocities' random numbers. Numbers are written with 17
significant digits, so the scene is exact to the bit.
"""
import argparse
import math
import random


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("n", type=int)
    ap.add_argument("out")
    ap.add_argument("--density", type=float, default=0.5)
    ap.add_argument("--speed", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--method", default="sesi2")
    ap.add_argument("--dt", type=float, default=0.002)
    ap.add_argument("--t-end", type=float, default=0.2)
    ap.add_argument("--output-every", type=int, default=100)
    a = ap.parse_args()
    if a.n < 2:
        ap.error("N must be >= 2")
    rng = random.Random(a.seed)
    radius = math.sqrt(a.n / (4 * math.pi * a.density))
    golden = math.pi * (3 - math.sqrt(5))
    lines = [f"# {a.n} Lennard-Jones bodies on S^2 at density {a.density} (tools/lattice_scene.py)",
             f'name = "lattice-s2-{a.n}"', "", "[space]", 'kind = "sphere"', "dim = 2", f"radius = {radius!r}", ""]
    for k in range(a.n):
        z = 1 - 2 * (k + 0.5) / a.n
        rho = math.sqrt(1 - z * z)
        x = [radius * rho * math.cos(k * golden), radius * rho * math.sin(k * golden), radius * z]
        v = [rng.gauss(0, a.speed) for _ in range(3)]
        dot = sum(xi * vi for xi, vi in zip(x, v)) / radius ** 2
        v = [vi - dot * xi for xi, vi in zip(x, v)]
        lines += ["[[bodies]]", "mass = 1.0", f"x = [{x[0]!r}, {x[1]!r}, {x[2]!r}]", f"v = [{v[0]!r}, {v[1]!r}, {v[2]!r}]"]
    lines += ["", "[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5", "",
              "[integrator]", f'method = "{a.method}"', f"dt = {a.dt!r}", f"t_end = {a.t_end!r}",
              f"output_every = {a.output_every}", ""]
    with open(a.out, "w") as f:
        f.write("\n".join(lines))


if __name__ == "__main__":
    main()
