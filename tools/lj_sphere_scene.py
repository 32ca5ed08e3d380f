#!/usr/bin/env python3
"""A Lennard-Jones scene on S^2 for timing the many-body step (issue #27; docs/benchmarks.md,
"Profile of a step"): N bodies on a Fibonacci lattice of the sphere at density 1/2 (radius
R = (N / (0.5 * 4 pi))^(1/2), nearest neighbours ~1.4 sigma apart), random tangent velocities
of unit temperature (seeded), epsilon = sigma = 1, cutoff 2.5, sesi2 with dt 0.002 for STEPS
steps: the scene of `sesi bench --scaling` at that N, as a file for `sesi run --profile`.
With --bodies FILE.csv the bodies go to that file (columns mass,x1,x2,x3,v1,v2,v3, repr() values,
which read back exactly) and the scene says bodies = "FILE.csv", written as given: the scene
reader resolves it relative to the scene file's directory, so write both into one directory
(docs/scene-format.md, "Bodies from a file"). At 10^6 bodies the scene then reads in a fraction
of the memory of [[bodies]] tables.

    python3 tools/lj_sphere_scene.py N STEPS > s2.toml
    cd DIR && python3 tools/lj_sphere_scene.py N STEPS --bodies s2-bodies.csv > s2.toml
"""
import math
import random
import sys


def main():
    args = sys.argv[1:]
    bodies_file = None
    if len(args) == 4 and args[2] == "--bodies":
        bodies_file = args[3]
        args = args[:2]
    if len(args) != 2:
        sys.exit("usage: lj_sphere_scene.py N STEPS [--bodies FILE.csv]")
    n, steps = int(args[0]), int(args[1])
    radius = math.sqrt(n / 0.5 / (4.0 * math.pi))
    golden = math.pi * (3.0 - math.sqrt(5.0))
    rng = random.Random(1)
    out = [f'name = "lj-s2-{n}"'] + ([f"bodies = {bodies_file!r}".replace("'", '"')] if bodies_file else []) + ["[space]", 'kind = "sphere"', "dim = 2", f"radius = {radius!r}",
           "[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5",
           "[integrator]", 'method = "sesi2"', "dt = 0.002", f"t_end = {steps * 0.002!r}", "neighbour_skin = 0.12"]
    csv = open(bodies_file, "w") if bodies_file else None
    if csv:
        csv.write("mass,x1,x2,x3,v1,v2,v3\n")
    for k in range(n):
        z = 1.0 - (2.0 * k + 1.0) / n
        r = math.sqrt(1.0 - z * z)
        x = [radius * r * math.cos(k * golden), radius * r * math.sin(k * golden), radius * z]
        v = [rng.gauss(0.0, 1.0) for _ in range(3)]
        dot = sum(a * b for a, b in zip(v, x)) / (radius * radius)
        v = [a - dot * b for a, b in zip(v, x)]
        if csv:
            csv.write(",".join(map(repr, [1.0] + x + v)) + "\n")
        else:
            out += ["[[bodies]]", "mass = 1.0", f"x = [{', '.join(map(repr, x))}]", f"v = [{', '.join(map(repr, v))}]"]
    if csv:
        csv.close()
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
