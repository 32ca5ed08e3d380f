#!/usr/bin/env python3
"""Tests of one simulation across MPI ranks (`mpiexec -np K sesi run SCENE`, issue #27;
docs/parallel.md), one ctest test per case (tests/ranks/CMakeLists.txt).

    check_ranks.py --list
    check_ranks.py --sesi PATH --source REPO --work DIR --case NAME --mpiexec PATH

Each case runs the built program plainly and under `mpiexec --oversubscribe -np K` (K = 1..4 on
CI's two cores) and asserts that the outputs are the plain run's byte for byte: a body's force is
summed over the same partners in the same order on any number of ranks (src/domain/
domain_integrator.hpp), so nothing may differ but the fields that say how the run ran. The scenes
are small (2000 bodies, a few hundred steps: about a second each) but long enough that bodies move
farther than half the domain skin (so the Verlet lists are rebuilt and the slabs cut again) and
cross the slabs' boundaries (so bodies change ranks). Standard library only. Exit status 0 passes, anything else
fails (the cases are registered only when the program has MPI: they never skip).
"""
import argparse
import csv
import json
import math
import os
import pathlib
import random
import shutil
import signal
import subprocess
import sys
import time

CASES = {}

# summary.json's fields that say how a run ran, not what it computed (docs/scene-format.md).
ENVIRONMENT = ("wall_seconds", "threads_used", "ranks", "threads_per_rank")
# The Lennard-Jones scenes: cutoff 2.5, neighbour_skin 0.12 (tools/lj_sphere_scene.py): the Verlet
# skin is 0.3 and the lists are rebuilt once a body has moved half of it; the ranks' domain skin is
# twice the Verlet skin (src/domain/domain_integrator.cpp), and the slabs are cut again once a body
# has moved half of that: 0.3, which covers both.
RECUT = 0.5 * (2.0 * 0.12 * 2.5)


def case(function):
    CASES[function.__name__] = function
    return function


class Failure(Exception):
    pass


def check(condition, message):
    if not condition:
        raise Failure(message)


class Context:
    def __init__(self, sesi, source, work, mpiexec):
        self.sesi = sesi
        self.source = pathlib.Path(source)
        self.work = pathlib.Path(work)
        self.mpiexec = mpiexec

    def command(self, args, ranks=None):
        """The command line and environment of `sesi ARGS`, under mpiexec -np ranks when given."""
        command = [self.sesi, *map(str, args)]
        env = dict(os.environ)
        if ranks is not None:
            # Open MPI refuses root unless told (CI runs as root in a container); four ranks on two
            # cores need --oversubscribe; containers often forbid the cross-memory attach of its
            # shared-memory transport. A waiting rank yields its core instead of polling: beside
            # the rest of `make test` (the sanitizer job's compiles) a polling case took 80 s of
            # CPU for 6 s of work, yielding 7 s.
            env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                       OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl_vader_single_copy_mechanism="none",
                       OMPI_MCA_mpi_yield_when_idle="1")
            command = [self.mpiexec, "--oversubscribe", "-np", str(ranks), *command]
        return command, env

    def run(self, *args, ranks=None, timeout=180):
        command, env = self.command(args, ranks)
        return subprocess.run(command, cwd=self.work, capture_output=True, text=True, timeout=timeout,
                              stdin=subprocess.DEVNULL, env=env)

    def write(self, name, text):
        path = self.work / name
        path.write_text(text)
        return path


def expect_ok(result, what):
    check(result.returncode == 0, f"{what}: exit status {result.returncode}; stderr: {result.stderr.strip()}")
    check("Traceback" not in result.stderr and "terminate called" not in result.stderr,
          f"{what}: crash: {result.stderr!r}")


# ---- scenes --------------------------------------------------------------------------------------

def sphere_scene(ctx, bodies, steps, name="s2.toml", extra=""):
    """tools/lj_sphere_scene.py's S^2 Lennard-Jones scene (the scene of sesi bench --scaling)."""
    text = subprocess.run([sys.executable, str(ctx.source / "tools" / "lj_sphere_scene.py"), str(bodies), str(steps)],
                          check=True, capture_output=True, text=True).stdout
    return ctx.write(name, text + extra)


def flat_scene(ctx, side, steps, seed=5):
    """E^3 Lennard-Jones: side^3 bodies on a cubic lattice at density 1/2 (spacing 2^(1/3)), each
    moved by up to 0.1 in every coordinate and given unit-temperature velocities (seeded), the
    mean momentum removed; an open cluster (no box) that starts to spread."""
    rng = random.Random(seed)
    spacing = 2.0 ** (1.0 / 3.0)
    points, velocities = [], []
    for i in range(side):
        for j in range(side):
            for k in range(side):
                points.append([spacing * c + rng.uniform(-0.1, 0.1) for c in (i, j, k)])
                velocities.append([rng.gauss(0.0, 1.0) for _ in range(3)])
    mean = [sum(v[c] for v in velocities) / len(velocities) for c in range(3)]
    lines = [f'name = "lj-e3-{len(points)}"', "[space]", 'kind = "euclidean"', "dim = 3",
             "[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5",
             "[integrator]", 'method = "sesi2"', "dt = 0.002", f"t_end = {steps * 0.002!r}", "neighbour_skin = 0.12"]
    for x, v in zip(points, velocities):
        # On E^n the chart is the identity: q = x, p = m v (m = 1).
        p = [v[c] - mean[c] for c in range(3)]
        lines += ["[[bodies]]", "mass = 1.0", f"q = [{', '.join(map(repr, x))}]", f"p = [{', '.join(map(repr, p))}]"]
    return ctx.write("e3.toml", "\n".join(lines) + "\n")


def box_scene(ctx, side, steps, drift=2.0, seed=9):
    """E^2 Lennard-Jones in a periodic box: side^2 bodies on a square lattice at density 1/2
    (spacing sqrt 2, the box side x sqrt 2 wide), jittered by up to 0.1, the first column 0.05 from
    the box's face; unit-temperature velocities (seeded) plus a drift along x, so that bodies
    cross the face (the run wraps them: image counts) and every slab's cuts along x."""
    rng = random.Random(seed)
    spacing = math.sqrt(2.0)
    edge = side * spacing
    lines = [f'name = "lj-box-{side * side}"', "[space]", 'kind = "euclidean"', "dim = 2", f"box = [{edge!r}, {edge!r}]",
             "[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5",
             "[integrator]", 'method = "sesi2"', "dt = 0.002", f"t_end = {steps * 0.002!r}", "neighbour_skin = 0.12"]
    for i in range(side):
        for j in range(side):
            x = [0.05 + spacing * i + rng.uniform(0.0, 0.1), spacing * (j + 0.5) + rng.uniform(-0.1, 0.1)]
            p = [rng.gauss(0.0, 1.0) + drift, rng.gauss(0.0, 1.0)]
            lines += ["[[bodies]]", "mass = 1.0", f"q = [{', '.join(map(repr, x))}]", f"p = [{', '.join(map(repr, p))}]"]
    return ctx.write("box.toml", "\n".join(lines) + "\n")


def hyperbolic_far_scene(ctx, side, steps, boost=10.0, seed=7):
    """H^2 (R = 20): side^2 bodies on a square grid of spacing 1.4 sigma about the origin, mapped by
    the exponential map, with unit-temperature tangent velocities (seeded), then boosted `boost`
    radii out along the first axis (as tests/program/run/cases_threads.py): a cluster 200 sigma
    from the chart's origin, held in a non-identity cluster frame."""
    rng = random.Random(seed)
    radius, spacing = 20.0, 1.4
    ch, sh = math.cosh(boost), math.sinh(boost)
    lines = [f'name = "lj-h2-far-{side * side}"', "[space]", 'kind = "hyperbolic"', "dim = 2", f"radius = {radius!r}",
             "[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5",
             "[integrator]", 'method = "sesi2"', "dt = 0.002", f"t_end = {steps * 0.002!r}", "neighbour_skin = 0.12"]
    for i in range(side * side):
        a, b = (i % side - (side - 1) / 2.0) * spacing, (i // side - (side - 1) / 2.0) * spacing
        r = math.hypot(a, b)
        u = [a / r, b / r] if r > 0 else [1.0, 0.0]
        x = [radius * math.sinh(r / radius) * u[0], radius * math.sinh(r / radius) * u[1],
             radius * math.cosh(r / radius)]
        v = [rng.gauss(0.0, 1.0) for _ in range(3)]
        # Tangent: remove the part along x in the Minkowski product (<x, x> = -R^2).
        dot = (v[0] * x[0] + v[1] * x[1] - v[2] * x[2]) / (-radius * radius)
        v = [c - dot * d for c, d in zip(v, x)]
        x = [ch * x[0] + sh * x[2], x[1], sh * x[0] + ch * x[2]]
        v = [ch * v[0] + sh * v[2], v[1], sh * v[0] + ch * v[2]]
        lines += ["[[bodies]]", "mass = 1.0", f"x = [{', '.join(map(repr, x))}]", f"v = [{', '.join(map(repr, v))}]"]
    return ctx.write("h2-far.toml", "\n".join(lines) + "\n")


def surface_scene(ctx, steps, radius=14.0, spacing=1.1, drift=2.0, seed=13):
    """Lennard-Jones on the compact surface of genus 2 (H^2 of radius R = 14 mod the group of the
    regular octagon D, include/sesi/topologies/hyperbolic_surface.hpp): bodies on rings about the
    origin (the first 0.55 sigma out), spacing 1.1 sigma along and between rings, kept where they lie at least spacing / 2
    inside every side of D (so that no two are closer than `spacing` across the sides either),
    with unit-temperature tangent velocities (seeded) plus a drift along the first axis (the boost
    field, speed `drift` at the origin), so that bodies cross D's sides (the run wraps them: their
    words) and the slabs' cuts."""
    rng = random.Random(seed)
    genus = 2
    sides = 4 * genus
    inradius = math.acosh(1.0 / math.tan(math.pi / sides))  # cosh r_in = cot(pi / 4g), radius 1
    # Side k's unit outward normal (radius 1): <y, n_k>_L is sinh of y's signed distance from its line.
    normals = [(math.cosh(inradius) * math.cos(2 * math.pi * k / sides),
                math.cosh(inradius) * math.sin(2 * math.pi * k / sides), math.sinh(inradius)) for k in range(sides)]
    inside = -math.sinh(0.5 * spacing / radius)
    lines = [f'name = "lj-surface-{genus}"', "[space]", 'kind = "hyperbolic"', "dim = 2", f"radius = {radius!r}",
             f"genus = {genus}", "[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0",
             "cutoff = 2.5", "[integrator]", 'method = "sesi2"', "dt = 0.002", f"t_end = {steps * 0.002!r}",
             "neighbour_skin = 0.12"]
    bodies = 0
    ring = 1  # (not at the origin: the chart's singular point)
    while ring * spacing < 2.5 * radius:  # D's circumradius: cosh r_c = cot^2(pi / 8), 2.45 R
        rho = (ring - 0.5) * spacing / radius
        count = max(1, int(2 * math.pi * radius * math.sinh(rho) / spacing))
        for j in range(count):
            phi = 2 * math.pi * (j + 0.5 * (ring % 2)) / count
            y = (math.sinh(rho) * math.cos(phi), math.sinh(rho) * math.sin(phi), math.cosh(rho))
            if max(y[0] * n[0] + y[1] * n[1] - y[2] * n[2] for n in normals) > inside:
                continue
            x = [radius * c for c in y]
            v = [rng.gauss(0.0, 1.0) for _ in range(3)]
            dot = (v[0] * x[0] + v[1] * x[1] - v[2] * x[2]) / (-radius * radius)
            v = [c - dot * d for c, d in zip(v, x)]  # tangent: <x, v>_L = 0
            # The boost along the first axis moves x by (x0, 0, x1) / R per unit of rapidity.
            v = [v[0] + drift * x[2] / radius, v[1], v[2] + drift * x[0] / radius]
            lines += ["[[bodies]]", "mass = 1.0", f"x = [{', '.join(map(repr, x))}]", f"v = [{', '.join(map(repr, v))}]"]
            bodies += 1
        ring += 1
    return ctx.write("surface.toml", "\n".join(lines) + "\n"), bodies


# ---- outputs -------------------------------------------------------------------------------------

def outputs(directory, keep_checkpoint=False):
    """An output directory's files by name, as bytes; summary.json parsed, less ENVIRONMENT."""
    files = {}
    for path in sorted(pathlib.Path(directory).iterdir()):
        if path.name == "checkpoint" and not keep_checkpoint:
            continue
        if path.name == "summary.json":
            data = json.loads(path.read_text())
            for key in ENVIRONMENT:
                data.pop(key, None)
            files[path.name] = data
        elif path.name == "sesi-manifest.txt" and not keep_checkpoint:
            # a resumed run always keeps a checkpoint: compare the manifests without it
            lines = path.read_text().splitlines()
            files[path.name] = [lines[0]] + [n for n in lines[1:] if n != "checkpoint"]
        else:
            files[path.name] = path.read_bytes()
    return files


def expect_same_outputs(mine, reference, what, keep_checkpoint=False):
    a, b = outputs(mine, keep_checkpoint), outputs(reference, keep_checkpoint)
    check(sorted(a) == sorted(b), f"{what}: files {sorted(a)}, the plain run's {sorted(b)}")
    for name in a:
        if a[name] != b[name]:
            if name == "summary.json":
                keys = sorted(k for k in set(a[name]) | set(b[name]) if a[name].get(k) != b[name].get(k))
                raise Failure(f"{what}: summary.json differs from the plain run's in {keys}")
            raise Failure(f"{what}: {name} differs from the plain run's")


def expect_run_environment(directory, ranks, threads, what):
    """summary.json says how many ranks and threads per rank ran (issue #27)."""
    data = json.loads((pathlib.Path(directory) / "summary.json").read_text())
    check(data.get("ranks") == ranks and data.get("threads_per_rank") == threads,
          f"{what}: summary.json has ranks {data.get('ranks')}, threads_per_rank {data.get('threads_per_rank')}; "
          f"expected {ranks} and {threads}")


def world_points(directory, dim):
    """The embedding points (x columns) of the first and the last row of trajectory.csv."""
    with open(pathlib.Path(directory) / "trajectory.csv", newline="") as f:
        reader = csv.reader(f)
        header = next(reader)
        first = last = None
        for row in reader:
            if first is None:
                first = row
            last = row
    bodies = sum(1 for name in header if name.endswith("_x1"))
    index = {name: k for k, name in enumerate(header)}

    def points(row):
        return [[float(row[index[f"b{b + 1}_x{c + 1}"]]) for c in range(dim)] for b in range(bodies)]

    return points(first), points(last)


def expect_rebuilds_and_migration(directory, space, ranks_tried, what):
    """The run exercised what a run across ranks must get right: some body moved farther than half
    the domain skin, so the Verlet lists were rebuilt and the slabs cut again; and, along every
    axis, some body's place in the order of that coordinate crossed a cut into K runs of equal
    count, so that slabs cut again along any axis hand it to another rank. space: (kind, radius,
    boost)."""
    kind, radius, boost = space
    start, end = world_points(directory, 3)
    if kind == "hyperbolic":
        # Back to the origin (the inverse of the scene's boost), where the world axes are the
        # cluster's own, and the Minkowski chord 2 R sinh(d / 2 R), which exceeds the distance d.
        ch, sh = math.cosh(boost), math.sinh(boost)
        start, end = ([[ch * x[0] - sh * x[2], x[1], -sh * x[0] + ch * x[2]] for x in points] for points in (start, end))
        half = 2.0 * radius * math.sinh(RECUT / (2.0 * radius))
        moved = max(math.sqrt(max((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 - (a[2] - b[2]) ** 2, 0.0))
                    for a, b in zip(start, end))
    else:
        # On S^2 the chord 2 R sin(d / 2 R) is below the distance d; on E^3 they are equal.
        half = RECUT
        moved = max(math.dist(a, b) for a, b in zip(start, end))
    check(moved > half,
          f"{what}: the farthest body moved a chord of {moved:.3f}, not more than {half:.3f} (half the domain skin)")
    # (H^2 at the origin: x3 is the height above the plane.)
    expect_slab_crossings(start, end, range(2 if kind == "hyperbolic" else 3), ranks_tried, what)


def expect_slab_crossings(start, end, axes, ranks_tried, what):
    """Along every axis, some body's place in the order of that coordinate (points start, end)
    crossed a cut into K runs of equal count, for every K >= 2 of ranks_tried."""
    n = len(start)
    for axis in axes:
        def slabs(points, k):
            order = sorted(range(n), key=lambda b: (points[b][axis], b))
            owner = [0] * n
            for place, b in enumerate(order):
                owner[b] = place * k // n
            return owner

        for k in ranks_tried:
            if k < 2:
                continue
            changed = sum(a != b for a, b in zip(slabs(start, k), slabs(end, k)))
            check(changed > 0, f"{what}: no body crossed a slab boundary of {k} slabs along axis {axis + 1}")


def same_on_every_count(ctx, scene, space, counts, extra=(), threads=1):
    """The plain run (one thread), then mpiexec -np K for every K of counts, `threads` threads per
    rank: the same files."""
    plain = ctx.work / "plain"
    args = ["--quiet", *extra]
    expect_ok(ctx.run("run", scene, "--out", plain, "--threads", 1, *args), "plain sesi run")
    expect_run_environment(plain, 1, 1, "plain sesi run")
    expect_rebuilds_and_migration(plain, space, counts, "plain sesi run")
    for ranks in counts:
        out = ctx.work / f"np{ranks}-threads{threads}"
        what = f"mpiexec -np {ranks} sesi run --threads {threads}"
        expect_ok(ctx.run("run", scene, "--out", out, "--threads", threads, *args, ranks=ranks), what)
        expect_same_outputs(out, plain, what)
        expect_run_environment(out, ranks, threads, what)
        shutil.rmtree(out)


def expect_plain_on_ranks(ctx, scene, plain, settings, counts, label):
    """mpiexec -np K sesi run scene with settings, for every K of counts: the files of the plain
    run in directory plain."""
    for ranks in counts:
        out = ctx.work / f"{label}-np{ranks}"
        what = f"mpiexec -np {ranks} sesi run ({label})"
        expect_ok(ctx.run("run", scene, "--out", out, *settings, ranks=ranks), what)
        expect_same_outputs(out, plain, what)
        shutil.rmtree(out)


def stopped_on_two_resumed_on_three(ctx, scene, what):
    """scene (300 steps of 0.002) run on 2 ranks to t = 0.3, then resumed on 3 to its end: the
    uninterrupted plain run's files, checkpoint at the end included."""
    settings = ["--output-every", "25", "--checkpoint-every", "40", "--threads", "1", "--quiet"]
    whole = ctx.work / f"whole-{what}"
    expect_ok(ctx.run("run", scene, "--out", whole, *settings), f"uninterrupted plain run ({what})")
    first = ctx.work / f"first-{what}"
    expect_ok(ctx.run("run", scene, "--out", first, "--t-end", "0.3", *settings, ranks=2),
              f"mpiexec -np 2 sesi run --t-end 0.3 ({what})")
    expect_ok(ctx.run("resume", first, "--t-end", "0.6", "--threads", "1", "--quiet", ranks=3),
              f"sesi resume on 3 ranks ({what})")
    expect_same_outputs(first, whole, f"{what} resumed on 3 ranks")
    check((first / "checkpoint").read_bytes() == (whole / "checkpoint").read_bytes(),
          f"the checkpoint at the end of the {what} run resumed on 3 ranks differs from the plain run's")


# ---- the cases -----------------------------------------------------------------------------------

@case
def ranks_sphere_lennard_jones(ctx):
    """S^2, 2000 bodies, 300 steps of sesi2: byte-identical outputs on 1, 2, 3 and 4 ranks of one
    thread, and on 2 ranks of 2 threads."""
    scene = sphere_scene(ctx, 2000, 300)
    space = ("sphere", math.sqrt(2000 / 0.5 / (4.0 * math.pi)), 0.0)
    same_on_every_count(ctx, scene, space, (1, 2, 3, 4), ["--output-every", "25"])
    # Threads inside the ranks: 2 ranks of 2 threads (1000 bodies a rank: two threads' loops).
    same_on_every_count(ctx, scene, space, (2,), ["--output-every", "25"], threads=2)


@case
def ranks_hyperbolic_far_lennard_jones(ctx):
    """H^2 200 sigma (10 R) from the chart's origin, 45^2 = 2025 bodies, 300 steps of sesi2: byte-identical
    outputs on 1, 2 and 3 ranks (the cluster frame is re-centred alike on every rank)."""
    scene = hyperbolic_far_scene(ctx, 45, 300)
    same_on_every_count(ctx, scene, ("hyperbolic", 20.0, 10.0), (1, 2, 3), ["--output-every", "25"])


@case
def ranks_flat_lennard_jones(ctx):
    """E^3, 14^3 = 2744 bodies, 300 steps of sesi2: byte-identical outputs on 1, 2, 3 and 4 ranks."""
    scene = flat_scene(ctx, 14, 300)
    same_on_every_count(ctx, scene, ("euclidean", 0.0, 0.0), (1, 2, 3, 4), ["--output-every", "25"])


@case
def ranks_resume_other_count(ctx):
    """A run on 2 ranks stopped half way (--t-end), resumed on 3 ranks and in one process: both equal
    the uninterrupted plain run (every file but the checkpoint, which each keeps at its own end)."""
    scene = sphere_scene(ctx, 2000, 300)
    settings = ["--output-every", "25", "--checkpoint-every", "40", "--threads", "1", "--quiet"]
    whole = ctx.work / "whole"
    expect_ok(ctx.run("run", scene, "--out", whole, *settings), "uninterrupted plain run")
    first = ctx.work / "first"
    expect_ok(ctx.run("run", scene, "--out", first, "--t-end", "0.3", *settings, ranks=2),
              "mpiexec -np 2 sesi run --t-end 0.3")
    check((first / "checkpoint").is_file(), "the run on 2 ranks kept no checkpoint")
    expect_run_environment(first, 2, 1, "mpiexec -np 2 sesi run --t-end 0.3")
    for ranks in (3, None):
        resumed = ctx.work / f"resumed-{ranks or 'plain'}"
        shutil.copytree(first, resumed)
        what = f"sesi resume on {ranks} ranks" if ranks else "plain sesi resume"
        expect_ok(ctx.run("resume", resumed, "--t-end", "0.6", "--threads", "1", "--quiet", ranks=ranks), what)
        expect_same_outputs(resumed, whole, what)
        expect_run_environment(resumed, ranks or 1, 1, what)
    # The checkpoints at the end are the same too: the state is the same to the bit.
    check((ctx.work / "resumed-3" / "checkpoint").read_bytes() == (whole / "checkpoint").read_bytes(),
          "the checkpoint at the end of the resumed run on 3 ranks differs from the plain run's")


@case
def ranks_periodic_box(ctx):
    """E^2 in a periodic box, 40^2 bodies drifting along x, 300 steps of sesi2: byte-identical
    outputs on 1, 2 and 3 ranks (the slabs are periodic along x; a body's image counts travel with
    it; the wrap is the whole run's call). Then a run on 2 ranks stopped half way and resumed on 3
    equals the uninterrupted plain run, checkpoint included."""
    scene = box_scene(ctx, 40, 300)
    settings = ["--output-every", "25", "--threads", "1", "--quiet"]
    plain = ctx.work / "plain-box"
    expect_ok(ctx.run("run", scene, "--out", plain, *settings), "plain sesi run (box)")
    # What the case must exercise: bodies wrapped across the face (non-zero image counts at the end).
    with open(plain / "trajectory.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, last = rows[0], rows[-1]
    wrapped = sum(1 for name, value in zip(header, last) if name.endswith("_n1") and int(float(value)) != 0)
    check(wrapped > 0, "no body crossed the box's face along x (all image counts 0)")
    expect_plain_on_ranks(ctx, scene, plain, settings, (1, 2, 3), "box")
    stopped_on_two_resumed_on_three(ctx, scene, "box")


def expect_surface_exercised(directory, ranks_tried):
    """A surface run exercised what a run across ranks must get right there: bodies wrapped back into
    D (words other than the identity at the end), some body moved (on its unwrapped points) farther
    than half the domain skin (Verlet rebuilds, cuts again), and along both axes some body's place
    in the order of its point in D crossed a cut into K runs of equal count (bodies change ranks)."""
    with open(pathlib.Path(directory) / "trajectory.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, first, last = rows[0], rows[1], rows[-1]
    index = {name: k for k, name in enumerate(header)}
    bodies = sum(1 for name in header if name.endswith("_word"))
    wrapped = sum(1 for b in range(bodies) if last[index[f"b{b + 1}_word"]] != "e")
    check(wrapped > 0, "no body crossed a side of the surface's polygon (every word the identity)")

    def column(row, field):
        return [[float(row[index[f"b{b + 1}_{field}{c + 1}"]]) for c in range(3)] for b in range(bodies)]

    radius = 14.0
    half = 2.0 * radius * math.sinh(RECUT / (2.0 * radius))  # the Minkowski chord of half the skin
    moved = max(math.sqrt(max((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 - (a[2] - b[2]) ** 2, 0.0))
                for a, b in zip(column(first, "u"), column(last, "u")))
    check(moved > half, f"the farthest body moved a chord of {moved:.3f}, not more than {half:.3f} (half the domain skin)")
    expect_slab_crossings(column(first, "x"), column(last, "x"), (0, 1), ranks_tried, "plain sesi run (surface)")


@case
def ranks_compact_surface(ctx):
    """The compact surface of genus 2 (H^2 of radius 14 mod the octagon's group), about 1900 bodies
    drifting along the first axis, 300 steps of sesi2: byte-identical outputs on 1, 2 and 3 ranks
    (a body's partners in the halo are found through the images of the bodies within the halo of
    the polygon; its group word travels with it; the wrap is the whole run's call). Then a run on 2
    ranks stopped half way and resumed on 3 equals the uninterrupted plain run, checkpoint included,
    and trajectory.h5 (H5MD) on 3 ranks is the plain run's."""
    scene, _ = surface_scene(ctx, 300)
    settings = ["--output-every", "25", "--threads", "1", "--quiet"]
    plain = ctx.work / "plain-surface"
    expect_ok(ctx.run("run", scene, "--out", plain, *settings), "plain sesi run (surface)")
    counts = (1, 2, 3)
    expect_surface_exercised(plain, counts)
    expect_plain_on_ranks(ctx, scene, plain, settings, counts, "surface")
    stopped_on_two_resumed_on_three(ctx, scene, "surface")
    # trajectory.h5's words and unwrapped points, which rank 0 holds whole (DomainIntegrator::own_state).
    expect_h5md_on_ranks(ctx, scene, (3,), "surface-h5md")


@case
def ranks_thermostats(ctx):
    """S^2, 2000 bodies, 300 steps under each thermostat (Langevin with a temperature schedule,
    Nose-Hoover, CSVR): byte-identical outputs on 2 and 3 ranks. The noise is keyed by a body's
    index in the whole run and the kinetic energy, N_f and the heat are summed over all ranks in
    body order (include/sesi/thermostat.hpp). Then a Langevin run on 2 ranks stopped half way and
    resumed on 3 equals the uninterrupted plain run, checkpoint included."""
    space = ("sphere", math.sqrt(2000 / 0.5 / (4.0 * math.pi)), 0.0)
    tables = {
        "langevin": 'kind = "langevin"\ntemperature = [[0.0, 1.0], [0.6, 1.5]]\ngamma = 2.0\nseed = 11\n',
        "nose-hoover": 'kind = "nose-hoover"\ntemperature = 1.2\ntau = 0.2\nchain = 3\n',
        "csvr": 'kind = "csvr"\ntemperature = 0.8\ntau = 0.1\nseed = 5\n',
    }
    for kind, table in tables.items():
        scene = sphere_scene(ctx, 2000, 300, f"{kind}.toml", "[thermostat]\n" + table)
        same_on_every_count(ctx, scene, space, (2, 3), ["--output-every", "25"])
    stopped_on_two_resumed_on_three(ctx, ctx.work / "langevin.toml", "Langevin")


def published(ctx, name):
    """The directory a run with --out work/name published (a stopped run's may be marked
    incomplete beside it)."""
    found = [p for p in ctx.work.iterdir() if p.is_dir() and (p.name == name or p.name.startswith(name + "."))]
    check(len(found) == 1, f"--out {name}: expected one published directory, found {sorted(p.name for p in found)}")
    return found[0]


def expect_h5md_on_ranks(ctx, scene, counts, label):
    """trajectory.h5 (H5MD, where sesi has HDF5) of scene on every K of counts: the plain run's
    files (without HDF5 the probe's refusal must say so)."""
    h5md = ["--trajectory-format", "h5md", "--output-every", "25", "--threads", "1", "--quiet"]
    probe = ctx.run("run", scene, "--out", ctx.work / f"{label}-probe", *h5md, "--t-end", "0.002")
    if probe.returncode != 0:
        check("HDF5" in probe.stderr or "h5md" in probe.stderr, f"H5MD probe: {probe.stderr.strip()}")
        return
    plain = ctx.work / f"{label}-plain"
    expect_ok(ctx.run("run", scene, "--out", plain, *h5md), f"plain sesi run ({label})")
    expect_plain_on_ranks(ctx, scene, plain, h5md, counts, label)


@case
def ranks_output_ends(ctx):
    """What rank 0 gathers in blocks of bodies from their owners (Snapshot::gather): trajectory.h5
    (H5MD, where sesi has HDF5) on 2 and 3 ranks, and a run stopped by the energy guard after a
    checked step between rows, whose outputs end at that last state known good (a row of it and
    summary.json's final state): the plain run's files on 2 and 3 ranks, exit status included."""
    scene = sphere_scene(ctx, 2000, 300)
    expect_h5md_on_ranks(ctx, scene, (2, 3), "h5md")
    # A guard so tight that it stops the run after some checks (every 7 steps) have passed: at
    # step 35, the last good step 28.
    text = scene.read_text().replace("neighbour_skin = 0.12\n", "neighbour_skin = 0.12\nenergy_guard = 2e-6\n", 1)
    scene = ctx.write("guarded.toml", text)
    settings = ["--output-every", "25", "--check-every", "7", "--threads", "1", "--quiet"]
    plain = ctx.run("run", scene, "--out", ctx.work / "guarded-plain", *settings)
    check(plain.returncode == 3, f"plain sesi run with a tight energy guard: exit status {plain.returncode}, not 3")
    reference = published(ctx, "guarded-plain")
    last = json.loads((reference / "summary.json").read_text())["final_state"]["step"]
    check(last % 25 != 0 and last > 7, f"the guarded run's last good step {last} is not a checked step between rows")
    for ranks in (2, 3):
        what = f"mpiexec -np {ranks} sesi run with a tight energy guard"
        result = ctx.run("run", scene, "--out", ctx.work / f"guarded-np{ranks}", *settings, ranks=ranks)
        check(result.returncode == 3, f"{what}: exit status {result.returncode}, not 3; stderr: {result.stderr.strip()}")
        expect_same_outputs(published(ctx, f"guarded-np{ranks}"), reference, what)


def gravity_sphere_scene(ctx, bodies, steps, name="gravity.toml"):
    """tools/lj_sphere_scene.py's S^2 bodies under cotangent gravity (G = 1/N, a pair term without a
    cutoff) instead of Lennard-Jones."""
    text = sphere_scene(ctx, bodies, steps, name).read_text()
    lj = 'kind = "lennard-jones"\nepsilon = 1.0\nsigma = 1.0\ncutoff = 2.5'
    check(lj in text, "tools/lj_sphere_scene.py's potential table changed")
    return ctx.write(name, text.replace(lj, f'kind = "cotangent-gravity"\nG = {1.0 / bodies!r}'))


@case
def ranks_long_range_sphere(ctx):
    """S^2, 320 bodies under cotangent gravity (a pair term without a cutoff: each rank sums its own
    bodies' rows against every body, the points gathered at every evaluation, in the order of one
    process's tiles), 300 steps of sesi2: byte-identical outputs on 1, 2 and 3 ranks, and a run on 2
    ranks stopped half way and resumed on 3 equals the uninterrupted plain run, checkpoint included."""
    scene = gravity_sphere_scene(ctx, 320, 300)
    settings = ["--output-every", "25", "--threads", "1", "--quiet"]
    plain = ctx.work / "plain-gravity"
    expect_ok(ctx.run("run", scene, "--out", plain, *settings), "plain sesi run (gravity)")
    for ranks in (1, 2, 3):
        out = ctx.work / f"gravity-np{ranks}"
        what = f"mpiexec -np {ranks} sesi run (gravity)"
        expect_ok(ctx.run("run", scene, "--out", out, *settings, ranks=ranks), what)
        expect_same_outputs(out, plain, what)
        shutil.rmtree(out)
    stopped_on_two_resumed_on_three(ctx, scene, "gravity")


@case
def ranks_long_range_hyperbolic_far(ctx):
    """H^2 200 sigma from the chart's origin, 17^2 bodies under Lennard-Jones and a weak harmonic
    pair term (a term without a cutoff beside a short-range one: the halo for the one, every body
    for the other), 150 steps of sesi2: byte-identical outputs on 1, 2 and 3 ranks."""
    scene = hyperbolic_far_scene(ctx, 17, 150)
    text = scene.read_text().replace("[integrator]", '[[potential]]\nkind = "harmonic-pair"\nk = 0.0001\n[integrator]', 1)
    scene = ctx.write("h2-far-harmonic.toml", text)
    settings = ["--output-every", "25", "--threads", "1", "--quiet"]
    plain = ctx.work / "plain-harmonic"
    expect_ok(ctx.run("run", scene, "--out", plain, *settings), "plain sesi run (harmonic)")
    for ranks in (1, 2, 3):
        out = ctx.work / f"harmonic-np{ranks}"
        what = f"mpiexec -np {ranks} sesi run (H^2, harmonic pairs)"
        expect_ok(ctx.run("run", scene, "--out", out, *settings, ranks=ranks), what)
        expect_same_outputs(out, plain, what)
        shutil.rmtree(out)


def rank_process(out, rank):
    """The pid of the `sesi run` of this case (its --out) that mpiexec started as `rank`, or None."""
    for entry in pathlib.Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            args = (entry / "cmdline").read_bytes().split(b"\0")
            environ = (entry / "environ").read_bytes().split(b"\0")
        except OSError:
            continue
        launcher = args[0].endswith((b"mpiexec", b"mpirun"))
        if str(out).encode() in args and b"run" in args and not launcher and \
                (f"OMPI_COMM_WORLD_RANK={rank}".encode() in environ or f"PMIX_RANK={rank}".encode() in environ):
            return int(entry.name)
    return None


@case
def ranks_killed_rank(ctx):
    """Rank 1 killed (SIGKILL) after a periodic checkpoint: mpiexec ends non-zero with a message, the
    last checkpoint is left whole, and a plain `sesi resume` from it equals an uninterrupted run."""
    scene = sphere_scene(ctx, 2000, 100000)  # 200 time units: far longer than the case waits
    out = ctx.work / "out"
    settings = ["--output-every", "10", "--checkpoint-every", "20", "--threads", "1", "--quiet"]
    command, env = ctx.command(["run", scene, "--out", out, *settings], ranks=2)
    process = subprocess.Popen(command, cwd=ctx.work, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               stdin=subprocess.DEVNULL, env=env)
    try:
        # Wait for the first periodic checkpoint in the staging directory (polled, not slept: a
        # loaded machine is slow), then kill rank 1 by its pid.
        deadline = time.monotonic() + 120
        staging = []
        while not staging and time.monotonic() < deadline and process.poll() is None:
            time.sleep(0.05)
            staging = [p for p in ctx.work.iterdir() if p.name.startswith(".out.sesi-") and (p / "checkpoint").exists()]
        check(bool(staging), f"no periodic checkpoint within 120 s (exit status {process.poll()})")
        victim = rank_process(out, 1)
        check(victim is not None, "no process of rank 1 found")
        os.kill(victim, signal.SIGKILL)
        _, stderr = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    err = stderr.decode(errors="replace")
    check(process.returncode != 0, "mpiexec exited 0 after rank 1 was killed")
    check(err.strip() != "", "no message on stderr after rank 1 was killed")
    # Whatever rank 0 did after its peer died, the checkpoint left is a whole one: sesi resume reads
    # it (checksummed) and goes on to 40 steps past it, equal to one run there.
    checkpoints = [p / "checkpoint" for p in ctx.work.iterdir()
                   if p.name.startswith(".out.sesi-") and (p / "checkpoint").exists()]
    if (out / "checkpoint").exists():
        checkpoints.append(out / "checkpoint")
    check(bool(checkpoints), "the checkpoint is gone")
    step = max(int(p.read_bytes().split(b"\nstep ")[1].split(b"\n")[0]) for p in checkpoints)
    check(step > 0 and step % 20 == 0, f"the checkpoint left is at step {step}, not a positive multiple of 20")
    print(f"rank 1 (pid {victim}) killed; mpiexec exit status {process.returncode}; checkpoint left at step {step}")
    t_end = f"{(step + 40) * 0.002:.3f}"
    expect_ok(ctx.run("resume", out, "--t-end", t_end, "--threads", "1", "--quiet"), "plain sesi resume after the kill")
    whole = ctx.work / "whole"
    expect_ok(ctx.run("run", scene, "--out", whole, "--t-end", t_end, *settings), "uninterrupted plain run")
    expect_same_outputs(out, whole, "resumed after rank 1 was killed")


@case
def ranks_refusals(ctx):
    """What a run across ranks does not support yet (src/domain/domain_integrator.hpp) is refused on
    2 ranks: exit status 2, one line from sesi naming it (mpiexec adds its own lines about the exit
    status), nothing written. The same scenes run in one process. The surface of genus 2 and radius
    1.8 allows a cutoff of 2.5 (1.5286 R) but the ranks' halo and the wrap's margin (2.5 + 4 x 0.3 +
    0.625) reach past its star of tiles (2.2568 R = 4.06)."""
    surface = ctx.write("surface-small.toml", "\n".join([
        'name = "surface"', "[space]", 'kind = "hyperbolic"', "dim = 2", "radius = 1.8", "genus = 2",
        "[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5",
        "[integrator]", 'method = "sesi2"', "dt = 0.005", "t_end = 0.05",
        "[[bodies]]", "mass = 1.0", "q = [0.1, 0.0]", "[[bodies]]", "mass = 1.0", "q = [1.2, 0.0]"]) + "\n")
    few = sphere_scene(ctx, 100, 10, "few.toml")
    geodesic = sphere_scene(ctx, 300, 10, "geodesic.toml")
    cases = [(surface, [], ["compact hyperbolic surface"]), (few, [], ["256"]),
             (geodesic, ["--method", "geodesic2"], ["geodesic2"])]
    # All three at once: mpiexec takes about a second to end a job whose ranks exit non-zero, mostly
    # waiting, so that together they take the time of one.
    started = []
    for scene, extra, _ in cases:
        command, env = ctx.command(["run", scene, "--out", ctx.work / f"out-{scene.stem}", "--quiet", *extra], ranks=2)
        started.append(subprocess.Popen(command, cwd=ctx.work, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        stdin=subprocess.DEVNULL, env=env, text=True))
    for (scene, extra, words), process in zip(cases, started):
        stdout, stderr = process.communicate(timeout=180)
        result = subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)
        out = ctx.work / f"out-{scene.stem}"
        what = f"mpiexec -np 2 sesi run {scene.name} {' '.join(extra)}"
        check(result.returncode == 2, f"{what}: exit status {result.returncode}, expected 2: {result.stderr!r}")
        mine = [line for line in result.stderr.splitlines() if line.startswith("sesi")]
        check(len(mine) == 1 and mine[0].startswith("sesi: error: "), f"{what}: sesi's lines on stderr: {mine!r}")
        check(any(w in mine[0] for w in words), f"{what}: the message names none of {words}: {mine[0]!r}")
        check(result.stdout == "", f"{what}: stdout {result.stdout!r}")
        check(not out.exists() and not [p for p in ctx.work.iterdir() if p.name.startswith(f".{out.name}.sesi-")],
              f"{what}: outputs were written")
        expect_ok(ctx.run("run", scene, "--out", ctx.work / f"plain-{scene.stem}", "--quiet", *extra),
                  f"plain sesi run {scene.name}")


# ---- driver --------------------------------------------------------------------------------------

def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--list", action="store_true")
    parser.add_argument("--sesi")
    parser.add_argument("--source", default=str(pathlib.Path(__file__).resolve().parent.parent.parent))
    parser.add_argument("--work")
    parser.add_argument("--case")
    parser.add_argument("--mpiexec")
    args = parser.parse_args()
    if args.list:
        print("\n".join(sorted(CASES)))
        return 0
    work = pathlib.Path(args.work) / args.case
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    ctx = Context(os.path.abspath(args.sesi), args.source, work, args.mpiexec)
    started = time.monotonic()
    try:
        CASES[args.case](ctx)
    except Failure as e:
        print(f"FAILED {args.case}: {e}")
        return 1
    print(f"passed {args.case} ({time.monotonic() - started:.1f} s)")
    shutil.rmtree(work, ignore_errors=True)  # the trajectories are megabytes
    return 0


if __name__ == "__main__":
    sys.exit(main())
