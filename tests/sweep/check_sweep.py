#!/usr/bin/env python3
"""Tests of `sesi sweep` (docs/sweeps.md), one ctest test per case (tests/sweep/CMakeLists.txt).

    check_sweep.py --list
    check_sweep.py --sesi PATH --source REPO --work DIR --case NAME [--mpiexec PATH]

Every sweep here is a few short runs of an example scene, so that the whole file takes seconds
on two cores. With --mpiexec (the program is built with MPI), the same sweep runs under
`mpiexec --oversubscribe -np K` for K = 1, 2, 3; without it those cases skip.
Standard library only. Exit status 0 passes, 77 skips (ctest SKIP_RETURN_CODE, with a "SKIPPED: reason"
line), anything else fails.
"""
import argparse
import csv
import json
import math
import os
import pathlib
import random
import re
import shutil
import signal
import subprocess
import sys
import time

# The program tests' driver holds the helpers every test of the program shares.
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / "program"))
from check_program import SKIP, Failure, Skip, check  # noqa: E402

CASES = {}


def case(function):
    CASES[function.__name__] = function
    return function


class Context:
    def __init__(self, sesi, source, work, mpiexec):
        self.sesi = sesi
        self.source = pathlib.Path(source)
        self.work = pathlib.Path(work)
        self.mpiexec = mpiexec

    def run(self, *args, cwd=None, ranks=None, timeout=120):
        command = [self.sesi, *map(str, args)]
        env = dict(os.environ)
        if ranks is not None:
            # Open MPI refuses root unless told (CI runs as root in a container).
            env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                       OMPI_MCA_rmaps_base_oversubscribe="1",
                       # containers often forbid the cross-memory attach of Open MPI's shared-memory transport
                       OMPI_MCA_btl_vader_single_copy_mechanism="none",
                       # a waiting rank yields its core instead of polling (tests/ranks/check_ranks.py)
                       OMPI_MCA_mpi_yield_when_idle="1")
            command = [self.mpiexec, "--oversubscribe", "-np", str(ranks), *command]
        return subprocess.run(command, cwd=cwd or self.work, capture_output=True, text=True,
                              timeout=timeout, stdin=subprocess.DEVNULL, env=env)

    def scene(self, name, t_end=None):
        """An example scene copied into the work directory, shortened to t_end."""
        text = (self.source / "examples" / "scenes" / name).read_text()
        if t_end is not None:
            lines = [f"t_end = {t_end}" if line.startswith("t_end") else line for line in text.splitlines()]
            text = "\n".join(lines) + "\n"
        path = self.work / name
        path.write_text(text)
        return path

    def write(self, name, text):
        path = self.work / name
        path.write_text(text)
        return path


def expect_status(result, status, what):
    check(result.returncode == status,
          f"{what}: exit status {result.returncode}, expected {status}; stderr: {result.stderr.strip()}")
    check("Traceback" not in result.stderr and "terminate called" not in result.stderr,
          f"{what}: crash: {result.stderr!r}")


def rows(out):
    with open(pathlib.Path(out) / "sweep.csv", newline="") as f:
        return list(csv.DictReader(f))


def run_dirs(out):
    return sorted(p for p in (pathlib.Path(out) / "runs").iterdir() if not p.name.startswith("."))


def outputs(directory):
    """A run's outputs as bytes, summary.json without its wall time (as the resume tests compare)."""
    files = {}
    for path in sorted(pathlib.Path(directory).iterdir()):
        if path.name == "summary.json":
            data = json.loads(path.read_text())
            data.pop("wall_seconds")
            data.pop("threads_per_rank", None)  # a sweep's runs may take --threads 1
            files[path.name] = data
        elif path.name in ("trajectory.csv", "trajectory.h5", "diagnostics.csv", "exact.csv", "checkpoint"):
            files[path.name] = path.read_bytes()
    return files


def expect_same_as_sesi_run(ctx, out):
    """Each run's outputs equal `sesi run DIR/runs/NNNN/scene.toml` byte for byte."""
    for run in run_dirs(out):
        reference = ctx.work / "reference" / out.name / run.name
        shutil.rmtree(reference, ignore_errors=True)
        result = ctx.run("run", "scene.toml", "--out", reference, "--quiet", cwd=run)
        expect_status(result, 0, f"sesi run {run}/scene.toml")
        mine, theirs = outputs(run), outputs(reference)
        if not (run / "trajectory.csv").exists():
            theirs.pop("trajectory.csv", None)  # the sweep keeps no trajectory unless asked
        check(mine and mine == theirs,
              f"{run}: outputs differ from sesi run of its scene.toml: {sorted(mine)} vs {sorted(theirs)}")


def file_tree(out):
    """Every run's files, less what says where and how long it ran (rank, host, wall time)."""
    tree = {}
    for run in run_dirs(out):
        for name, data in outputs(run).items():
            tree[f"{run.name}/{name}"] = data
        tree[f"{run.name}/scene.toml"] = (run / "scene.toml").read_bytes()
    table = [{k: v for k, v in row.items() if k not in ("wall_seconds", "rank", "host")} for row in rows(out)]
    return tree, table


# ---- scenes and sweeps ---------------------------------------------------------------------------

def two_body_sweep(ctx, name="sweep.toml", extra=""):
    """2 steps x 2 perturbed copies of body 0's x: 4 runs of the two bodies on S^2 (x/v)."""
    ctx.scene("sphere-two-body-xv.toml", t_end=0.5)
    return ctx.write(name, f"""scene = "sphere-two-body-xv.toml"
{extra}
[[vary]]
key = "integrator.dt"
range = [0.01, 0.02, 2]  # the same as values = [0.01, 0.02]

[[vary]]
key = "bodies.0.x"
perturb = 1e-3
count = 2
seed = 7
""")


def mt19937_64(seed):
    """std::mt19937_64, as the C++ standard specifies it: the generator of docs/sweeps.md."""
    n, m, mask = 312, 156, (1 << 64) - 1
    state = [seed & mask]
    for i in range(1, n):
        state.append((6364136223846793005 * (state[-1] ^ (state[-1] >> 62)) + i) & mask)
    index = n
    while True:
        if index >= n:
            for i in range(n):
                x = (state[i] & 0xFFFFFFFF80000000) | (state[(i + 1) % n] & 0x7FFFFFFF)
                state[i] = state[(i + m) % n] ^ (x >> 1) ^ (0xB5026F5AA96619E9 if x & 1 else 0)
            index = 0
        y = state[index]
        index += 1
        y ^= (y >> 29) & 0x5555555555555555
        y ^= (y << 17) & 0x71D67FFFEDA60000
        y ^= (y << 37) & 0xFFF7EEE000000000
        y ^= y >> 43
        yield y & mask


def draws(seed, copy, count):
    """Component i of copy k: 2 u - 1, u the 53 high bits of a draw of mt19937_64(seed + k)."""
    engine = mt19937_64(seed + copy)
    return [2.0 * ((next(engine) >> 11) * 2.0 ** -53) - 1.0 for _ in range(count)]


# ---- the cases -----------------------------------------------------------------------------------

@case
def sweep_product_same_as_run(ctx):
    """The Cartesian product, in order; each run's outputs are those of sesi run of its scene."""
    sweep = two_body_sweep(ctx)
    out = ctx.work / "out"
    result = ctx.run("sweep", sweep, "--out", out, "--jobs", "2")
    expect_status(result, 0, "sesi sweep")
    table = rows(out)
    check([r["index"] for r in table] == ["0", "1", "2", "3"], f"rows: {[r['index'] for r in table]}")
    check([r["integrator.dt"] for r in table] == ["0.01", "0.01", "0.02", "0.02"], "the first [[vary]] varies slowest")
    check(table[0]["bodies.0.x.0"] == table[2]["bodies.0.x.0"] != table[1]["bodies.0.x.0"],
          "copy k of a perturbation is the same for every value of the other keys")
    for row in table:
        check(row["status"] == "ok" and row["exit_status"] == "0", f"run {row['index']}: {row}")
        check(float(row["max_energy_error"]) > 0 and abs(float(row["final_energy_error"])) <= float(row["max_energy_error"]),
              f"energy errors of run {row['index']}: {row}")
        check(row["rank"] == "0" and row["host"], f"rank and host of run {row['index']}: {row}")
    for run in run_dirs(out):
        names = {p.name for p in run.iterdir()}
        check({"scene.toml", "log.txt", "sweep-run.toml", "diagnostics.csv", "summary.json"} <= names, f"{run}: {names}")
        check("trajectory.csv" not in names, f"{run}: the trajectory is off unless the sweep asks for it")
    expect_same_as_sesi_run(ctx, out)
    # One process at a time gives the same files.
    out1 = ctx.work / "out-jobs1"
    expect_status(ctx.run("sweep", sweep, "--out", out1, "--jobs", "1", "--quiet"), 0, "sesi sweep --jobs 1")
    check(file_tree(out1) == file_tree(out), "--jobs 1 and --jobs 2 differ")
    # With trajectory = true, the trajectory is kept, and equals sesi run's.
    sweep_t = two_body_sweep(ctx, "sweep-trajectory.toml", extra="trajectory = true")
    out_t = ctx.work / "out-trajectory"
    expect_status(ctx.run("sweep", sweep_t, "--out", out_t, "-q"), 0, "sesi sweep (trajectory)")
    check(all((run / "trajectory.csv").exists() for run in run_dirs(out_t)), "trajectory = true keeps trajectory.csv")
    expect_same_as_sesi_run(ctx, out_t)


@case
def sweep_mpi_ranks(ctx):
    """1, 2 and 3 ranks: the same files, each as sesi run writes it; runs handed out to ranks > 0."""
    if not ctx.mpiexec:
        raise Skip("sesi is built without MPI (SESI_BUILD_MPI, libopenmpi-dev)")
    sweep = two_body_sweep(ctx)
    trees = []
    for ranks in (1, 2, 3):
        out = ctx.work / f"out-np{ranks}"
        result = ctx.run("sweep", sweep, "--out", out, ranks=ranks)
        expect_status(result, 0, f"mpiexec -np {ranks} sesi sweep")
        used = {row["rank"] for row in rows(out)}
        check(used == {"0"} if ranks == 1 else "0" not in used and used <= {str(r) for r in range(1, ranks)},
              f"{ranks} ranks: runs done by ranks {used}")
        trees.append(file_tree(out))
        if ranks == 3:
            expect_same_as_sesi_run(ctx, out)
    check(trees[0] == trees[1] == trees[2], "the outputs depend on the number of ranks")
    # A failing run under MPI: recorded, the others go on, exit status 3 from mpiexec.
    failing = ctx.write("failing.toml", f"""scene = "sphere-two-body-xv.toml"
[[vary]]
key = "integrator.energy_guard"
values = [100.0, 1e-12, 100.0]
""")
    out = ctx.work / "out-failing"
    expect_status(ctx.run("sweep", failing, "--out", out, ranks=2), 3, "mpiexec -np 2 sesi sweep (a failing run)")
    check([row["status"] for row in rows(out)] == ["ok", "failed", "ok"], f"statuses: {rows(out)}")


@case
def sweep_mpi_thermostat(ctx):
    """A thermostatted sweep (issue #25): the noise is keyed by the run's seed and step, never by the
    rank, so 1 and 2 ranks write the same files, each as sesi run writes it."""
    if not ctx.mpiexec:
        raise Skip("sesi is built without MPI (SESI_BUILD_MPI, libopenmpi-dev)")
    text = ctx.scene("sphere-two-body-xv.toml", t_end=0.3).read_text().replace('method = "sesi4"', 'method = "sesi2"')
    ctx.write("thermostat-scene.toml", text + """
[thermostat]
kind = "langevin"
temperature = 0.5
gamma = 2.0
seed = 11
""")
    sweep = ctx.write("thermostat-sweep.toml", """scene = "thermostat-scene.toml"

[[vary]]
key = "thermostat.seed"
values = [1, 2, 3]
""")
    trees = []
    for ranks in (1, 2):
        out = ctx.work / f"out-thermostat-np{ranks}"
        expect_status(ctx.run("sweep", sweep, "--out", out, ranks=ranks), 0, f"mpiexec -np {ranks} sesi sweep")
        trees.append(file_tree(out))
        if ranks == 2:
            expect_same_as_sesi_run(ctx, out)
    check(trees[0] == trees[1], "a thermostatted sweep's outputs depend on the number of ranks")
    noise = {data for name, data in trees[0][0].items() if name.endswith("diagnostics.csv")}
    check(len(noise) == 3, "the three thermostat seeds gave fewer than three different runs")
    # sweep.csv's energy-error columns are those of the conserved quantity the guard judges, not of
    # the energy, which changes by the heat on purpose.
    out = ctx.work / "out-thermostat-np1"
    for row, run in zip(rows(out), run_dirs(out)):
        conserved = json.loads((run / "summary.json").read_text())["thermostat"]["conserved"]
        check(float(row["max_energy_error"]) == conserved["max_abs_drift"] and
              float(row["final_energy_error"]) == conserved["final"] - conserved["initial"],
              f"{run.name}: sweep.csv's energy errors {row} are not the conserved quantity's {conserved}")


@case
def sweep_perturb(ctx):
    """Perturbations: the documented generator, reproducible from the seed, kept on the space."""
    sweep = two_body_sweep(ctx)
    out_a, out_b = ctx.work / "a", ctx.work / "b"
    for out in (out_a, out_b):
        expect_status(ctx.run("sweep", sweep, "--out", out, "-q"), 0, "sesi sweep")
    check(rows(out_a) and [r["bodies.0.x.0"] for r in rows(out_a)] == [r["bodies.0.x.0"] for r in rows(out_b)],
          "the same seed gives other values")
    base = [0.9320390859672263, 0.0, 0.3623577544766736]
    for row in rows(out_a):
        copy = int(row["index"]) % 2
        x = [float(row[f"bodies.0.x.{i}"]) for i in range(3)]
        raw = [b + 1e-3 * d for b, d in zip(base, draws(7, copy, 3))]
        scale = 1.0 / math.sqrt(sum(c * c for c in raw))  # as the program scales: R / |x|
        expected = [c * scale for c in raw]
        check(all(abs(a - b) <= 4e-16 for a, b in zip(x, expected)),
              f"run {row['index']}: x = {x}, expected the documented draws {expected}")
        check(abs(math.sqrt(sum(c * c for c in x)) - 1.0) < 4e-16, f"run {row['index']}: x is off the sphere")
        scene = (out_a / "runs" / f"{int(row['index']):04d}" / "scene.toml").read_text()
        v = json.loads(scene.split("v = ", 1)[1].split("\n", 1)[0])
        check(abs(sum(a * b for a, b in zip(x, v))) < 1e-15, f"run {row['index']}: v not tangent at the new x")
    other = ctx.write("other-seed.toml", sweep.read_text().replace("seed = 7", "seed = 8"))
    out_c = ctx.work / "c"
    expect_status(ctx.run("sweep", other, "--out", out_c, "-q"), 0, "sesi sweep (seed 8)")
    check([r["bodies.0.x.0"] for r in rows(out_c)] != [r["bodies.0.x.0"] for r in rows(out_a)],
          "another seed gives the same values")
    # On H^2: the point stays on the upper sheet of the hyperboloid, the velocity tangent.
    ctx.scene("hyperbolic-kepler-xv.toml", t_end=0.2)
    hyper = ctx.write("hyperbolic.toml", """scene = "hyperbolic-kepler-xv.toml"
[[vary]]
key = "bodies.0.x"
perturb = 1e-2
count = 3
seed = 1
[[vary]]
key = "bodies.1.v"
perturb = 1e-2
count = 1
""")
    out_h = ctx.work / "h"
    expect_status(ctx.run("sweep", hyper, "--out", out_h, "-q"), 0, "sesi sweep on H^2")
    for row in rows(out_h):
        x = [float(row[f"bodies.0.x.{i}"]) for i in range(3)]
        check(abs(x[0] ** 2 + x[1] ** 2 - x[2] ** 2 + 1.0) < 4e-16 * x[2] ** 2 and x[2] > 0,
              f"H^2: x = {x} off the upper sheet")


@case
def sweep_failure_and_rerun(ctx):
    """A failing run is recorded and the sweep goes on (exit 3); a rerun skips what is done."""
    ctx.scene("sphere-two-body-xv.toml", t_end=0.5)
    sweep = ctx.write("sweep.toml", """scene = "sphere-two-body-xv.toml"
[[vary]]
key = "integrator.energy_guard"
values = [100.0, 1e-12, 100.0, 50]
""")
    out = ctx.work / "out"
    result = ctx.run("sweep", sweep, "--out", out)
    expect_status(result, 3, "sesi sweep with a failing run")
    table = rows(out)
    check([r["status"] for r in table] == ["ok", "failed", "ok", "ok"], f"statuses: {[r['status'] for r in table]}")
    check(table[1]["exit_status"] == "3" and "energy" in table[1]["message"], f"the failed run's row: {table[1]}")
    check("sesi: error:" in (out / "runs" / "0001" / "log.txt").read_text(), "the failed run's log.txt has its error")
    check(json.loads((out / "runs" / "0001" / "summary.json").read_text())["complete"] is False, "run 1 incomplete")

    def stamps():
        return {p.relative_to(out).as_posix(): p.stat().st_mtime_ns for p in (out / "runs").rglob("*")}

    before = stamps()
    time.sleep(0.02)
    again = ctx.run("sweep", sweep, "--out", out)
    expect_status(again, 3, "rerun (the failed run is kept: it fails the same way)")
    check(stamps() == before, "a rerun rewrote runs that were done")
    check("4 done before" in again.stdout, f"rerun report: {again.stdout!r}")
    check(rows(out) == table, "sweep.csv changed on a rerun that ran nothing")

    # A removed run, a killed sweep's staging folder and a changed value are redone; nothing else.
    shutil.rmtree(out / "runs" / "0002")
    stale = out / "runs" / ".0003.sweep-abcdef"
    stale.mkdir()
    (stale / "scene.toml").write_text("half written\n")
    (out / "runs" / "0000" / "plot.png").write_bytes(b"a user's plot")
    sweep.write_text(sweep.read_text().replace("50]", "60]"))
    before = stamps()
    again = ctx.run("sweep", sweep, "--out", out)
    expect_status(again, 3, "rerun after changes")
    after = stamps()
    check(not stale.exists(), "the killed sweep's staging folder was left")
    for name in ("0000", "0001"):
        check(after[f"runs/{name}/summary.json"] == before[f"runs/{name}/summary.json"], f"run {name} was redone")
    check((out / "runs" / "0002" / "summary.json").exists(), "the removed run was not redone")
    check(after["runs/0003/summary.json"] != before["runs/0003/summary.json"], "the changed run was not redone")
    check(rows(out)[3]["integrator.energy_guard"] == "60", f"sweep.csv: {rows(out)[3]}")
    check((out / "runs" / "0000" / "plot.png").exists(), "a file added to a done run was removed")
    check(not [p for p in (out / "runs").iterdir() if p.name.startswith(".")], "staging folders left behind")

    # A run to redo that holds a file sesi did not write: refused, untouched.
    (out / "runs" / "0003" / "sweep-run.toml").unlink()
    (out / "runs" / "0003" / "notes.txt").write_text("mine\n")
    before = stamps()
    refused = ctx.run("sweep", sweep, "--out", out)
    expect_input_error(refused, "runs/0003")
    check(stamps() == before, "a refused rerun changed the runs")


def expect_input_error(result, text=""):
    """Exit status 2, one line on stderr naming what is wrong, nothing on stdout."""
    err = result.stderr
    check(result.returncode == 2, f"exit status {result.returncode}, expected 2; stderr: {err!r}")
    check(result.stdout == "", f"stdout should be empty, got {result.stdout!r}")
    check(err.endswith("\n") and err.count("\n") == 1 and err.startswith("sesi: error: "),
          f"expected one line 'sesi: error: ...' on stderr, got {err!r}")
    check(text in err, f"stderr does not say {text!r}: {err!r}")


BAD_SWEEPS = {
    # name: (sweep file, what stderr says)
    "missing_scene": ('scene = "nope.toml"\n[[vary]]\nkey = "integrator.dt"\nvalues = [0.1]\n', "nope.toml"),
    "unknown_key": ('scene = "S"\n[[vary]]\nkey = "integrator.dtt"\nvalues = [0.1]\n', "did you mean 'dt'"),
    "off_the_space": ('scene = "S"\n[[vary]]\nkey = "bodies.0.x"\nvalues = [[1.0, 1.0, 0.0]]\n', "not on the sphere"),
    "bad_value": ('scene = "S"\n[[vary]]\nkey = "integrator.dt"\nvalues = [0.01, 0.0]\n', "run 0001"),
    "no_such_body": ('scene = "S"\n[[vary]]\nkey = "bodies.2.x"\nperturb = 1e-6\ncount = 2\n', "no entry 2"),
    "bad_perturb": ('scene = "S"\n[[vary]]\nkey = "bodies.0.x"\nperturb = -1e-6\ncount = 2\n', "perturb"),
    "bad_count": ('scene = "S"\n[[vary]]\nkey = "bodies.0.x"\nperturb = 1e-6\ncount = 0\n', "count"),
    "perturb_text": ('scene = "S"\n[[vary]]\nkey = "name"\nperturb = 1e-6\ncount = 2\n', "array of numbers"),
    "values_and_perturb": ('scene = "S"\n[[vary]]\nkey = "integrator.dt"\nvalues = [0.1]\nperturb = 1.0\n',
                           "not several"),
    "bad_range": ('scene = "S"\n[[vary]]\nkey = "integrator.dt"\nrange = [0.1, 0.2]\n', "range"),
    "unknown_top_key": ('scene = "S"\n[[vari]]\nkey = "integrator.dt"\nvalues = [0.1]\n', "did you mean 'vary'"),
    "no_vary": ('scene = "S"\n', "[[vary]]"),
    "twice": ('scene = "S"\n[[vary]]\nkey = "integrator.dt"\nvalues = [0.1]\n[[vary]]\nkey = "integrator.dt"\n'
              'values = [0.2]\n', "varied twice"),
    "syntax": ('scene = "S"\n[[vary]\n', "TOML syntax error"),
}


@case
def sweep_bad_input(ctx):
    """Each bad sweep file: exit status 2, one line naming the problem, nothing written."""
    ctx.scene("sphere-two-body-xv.toml", t_end=0.5)
    for name, (text, message) in BAD_SWEEPS.items():
        sweep = ctx.write(f"{name}.toml", text.replace('"S"', '"sphere-two-body-xv.toml"'))
        out = ctx.work / f"out-{name}"
        try:
            expect_input_error(ctx.run("sweep", sweep, "--out", out), message)
        except Failure as e:
            raise Failure(f"{name}: {e}")
        check(not out.exists(), f"{name}: {out} was written")
    good = ctx.write("good.toml", BAD_SWEEPS["unknown_key"][0].replace('"S"', '"sphere-two-body-xv.toml"')
                     .replace("dtt", "dt"))
    expect_input_error(ctx.run("sweep", good, "--out", ctx.work / "j", "--jobs", "0"), "--jobs")
    # A directory holding a sweep.csv that sesi did not write, or a foreign runs/NNNN: refused.
    for name, make in (("csv", lambda d: (d / "sweep.csv").write_text("mine\n")),
                       ("runs", lambda d: ((d / "runs" / "0000").mkdir(parents=True),
                                           (d / "runs" / "0000" / "data.txt").write_text("mine\n")))):
        out = ctx.work / f"foreign-{name}"
        out.mkdir()
        make(out)
        before = sorted((p.relative_to(out), p.stat().st_mtime_ns) for p in out.rglob("*"))
        expect_input_error(ctx.run("sweep", good, "--out", out), "sesi did not write")
        after = sorted((p.relative_to(out), p.stat().st_mtime_ns) for p in out.rglob("*"))
        check(before == after, f"foreign {name}: the directory was changed")


@case
def sweep_examples_check(ctx):
    """The example sweeps (examples/sweeps/*.toml) are valid: --check reads every variant, runs nothing."""
    sweeps = [p for p in sorted((ctx.source / "examples" / "sweeps").glob("*.toml"))
              if p.read_text().lstrip().startswith(("#", "scene")) and "[[vary]]" in p.read_text()]
    check(sweeps, "no example sweeps")
    for sweep in sweeps:
        result = ctx.run("sweep", sweep, "--check", "--out", ctx.work / "never")
        expect_status(result, 0, f"sesi sweep {sweep.name} --check")
        check(" runs, every variant a valid scene" in result.stdout, f"{sweep.name}: {result.stdout!r}")
        check(not (ctx.work / "never").exists(), "--check wrote outputs")
        result = ctx.run("run", sweep.parent / (sweep.read_text().split('scene = "')[1].split('"')[0]), "--t-end", "0.5",
                         "--out", ctx.work / "base", "-q")
        expect_status(result, 0, f"the base scene of {sweep.name}")


@case
def sweep_interrupted(ctx):
    """SIGINT stops the sweep (exit 130); sweep.csv claims only the runs done; a rerun does the rest."""
    ctx.scene("sphere-two-body-xv.toml", t_end=0.2)
    sweep = ctx.write("sweep.toml", """scene = "sphere-two-body-xv.toml"
[[vary]]
key = "integrator.t_end"
values = [0.2, 1e4, 0.2]
""")
    out = ctx.work / "out"
    process = subprocess.Popen([ctx.sesi, "sweep", str(sweep), "--out", str(out), "--jobs", "1"], cwd=ctx.work,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    deadline = time.time() + 20
    while time.time() < deadline and not (out / "runs" / "0000").exists():
        time.sleep(0.05)
    time.sleep(0.3)  # run 1 (t_end = 1e4, some 20 s) is going
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=60)
    check(process.returncode == 130, f"exit status {process.returncode}, expected 130; stderr {stderr!r}")
    check([r["status"] for r in rows(out)] == ["ok", "pending", "pending"], f"sweep.csv after SIGINT: {rows(out)}")
    check([p.name for p in (out / "runs").iterdir()] == ["0000"], f"runs left: {list((out / 'runs').iterdir())}")
    # Rerun with a shorter run 1: the rest is done.
    sweep.write_text(sweep.read_text().replace("1e4", "0.4"))
    expect_status(ctx.run("sweep", sweep, "--out", out, "-q"), 0, "rerun")
    check([r["status"] for r in rows(out)] == ["ok"] * 3, f"after the rerun: {rows(out)}")


# ---- issue #24: linear checking and its cap, live runs of a killed sweep, threads, long input -----

CAP = 100_000  # max_sweep_runs, src/sweep/sweep_file.hpp


@case
def sweep_check_cap_linear(ctx):
    """A sweep at the cap (10^5 runs from one values array, and from one range) checks: building
    the variants used to copy the whole array per variant (10^5 did not end in 120 s, ctest's
    TIMEOUT; it takes some 4 s now). One over the cap is refused with the cap and its reason."""
    ctx.scene("sphere-two-body-xv.toml", t_end=0.5)
    head = 'scene = "sphere-two-body-xv.toml"\n[[vary]]\nkey = "integrator.dt"\n'
    values = ctx.write("values.toml", head + "values = [" + ", ".join(repr(0.001 + 1e-9 * i) for i in range(CAP)) + "]\n")
    ranged = ctx.write("range.toml", head + f"range = [0.001, 0.002, {CAP}]\n")
    for sweep in (values, ranged):
        try:
            result = ctx.run("sweep", sweep, "--check", "--out", ctx.work / "never")
        except subprocess.TimeoutExpired:  # the hang guard, as ctest's TIMEOUT
            raise Failure(f"sesi sweep {sweep.name} --check did not end in 120 s (quadratic checking?)")
        expect_status(result, 0, f"sesi sweep {sweep.name} --check")
        check(f"{CAP} runs, every variant a valid scene" in result.stdout, f"{sweep.name}: {result.stdout!r}")
    check(not (ctx.work / "never").exists(), "--check wrote outputs")
    over = {
        "range": head + f"range = [0.001, 0.002, {CAP + 1}]\n",
        "count": 'scene = "sphere-two-body-xv.toml"\n[[vary]]\nkey = "bodies.0.x"\nperturb = 1e-6\n'
                 f"count = {CAP + 1}\n",
        "values": head + "values = [" + ", ".join(repr(0.001 + 1e-9 * i) for i in range(CAP + 1)) + "]\n",
        "product": head + "range = [0.001, 0.002, 400]\n[[vary]]\nkey = \"integrator.t_end\"\n"
                   "range = [0.1, 0.2, 300]\n",
    }
    for name, text in over.items():
        out = ctx.work / f"out-{name}"
        result = ctx.run("sweep", ctx.write(f"over-{name}.toml", text), "--out", out)
        try:
            expect_input_error(result, f"over the cap of {CAP} runs in one sweep (each run is a process")
        except Failure as e:
            raise Failure(f"{name}: {e}")
        check("integer >= 2" not in result.stderr, f"{name}: {result.stderr!r}")
        check(not out.exists(), f"{name}: {out} was written")


def processes_in(directory):
    """The ids of the processes whose working directory is `directory` (a sweep's runs)."""
    found = []
    for proc in pathlib.Path("/proc").iterdir():
        try:
            if proc.name.isdigit() and os.readlink(proc / "cwd") == str(directory):
                found.append(int(proc.name))
        except OSError:
            pass
    return found


def alive(pid):
    """Running, not a zombie (an orphan stays one until something reaps it)."""
    try:
        return (pathlib.Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] not in "ZXx"
    except (OSError, IndexError):
        return False


@case
def sweep_rerun_keeps_live_runs(ctx):
    """A sweep killed with SIGKILL leaves its running run going (its own process group); a rerun
    refuses while it goes and keeps its staging folder, and removes the folder once it has ended."""
    ctx.scene("sphere-two-body-xv.toml", t_end=0.2)
    sweep = ctx.write("sweep.toml", """scene = "sphere-two-body-xv.toml"
[[vary]]
key = "integrator.t_end"
values = [1e4, 0.2]
""")
    out = ctx.work / "out"
    process = subprocess.Popen([ctx.sesi, "sweep", str(sweep), "--out", str(out), "--jobs", "1"], cwd=ctx.work,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
    children = []
    try:
        deadline = time.time() + 30
        staging = []
        while time.time() < deadline and not children:
            staging = list((out / "runs").glob(".0000.sweep-*")) if (out / "runs").exists() else []
            children = [pid for folder in staging for pid in processes_in(folder)]
            time.sleep(0.05)
        check(len(staging) == 1 and len(children) == 1, f"run 0000 did not start: {staging}, {children}")
        process.kill()  # the sweep only, as the OOM killer or a scheduler would
        process.wait(timeout=30)
        check(alive(children[0]), "the run ended with its sweep")
        refused = ctx.run("sweep", sweep, "--out", out)
        expect_input_error(refused, f"run 0000 of an earlier sweep is still running in runs/{staging[0].name} "
                                    f"(pid {children[0]})")
        check(staging[0].is_dir() and alive(children[0]), "the live run's staging folder was removed")
        marker = (staging[0] / ".sesi-sweep-staging").read_text().split()
        check(marker and marker[0] == str(children[0]), f"the staging marker holds {marker}, not the run's pid")
    finally:
        if process.poll() is None:
            process.kill()
        for pid in children:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
    deadline = time.time() + 30
    while time.time() < deadline and any(alive(pid) for pid in children):
        time.sleep(0.05)
    # The run has ended: a rerun removes its folder and does both runs.
    sweep.write_text(sweep.read_text().replace("1e4", "0.2"))
    result = ctx.run("sweep", sweep, "--out", out, "-q")
    expect_status(result, 0, "rerun after the killed sweep's run ended")
    check("removed the staging folders of killed runs: " + staging[0].name in result.stderr, f"{result.stderr!r}")
    check([p.name for p in sorted((out / "runs").iterdir())] == ["0000", "0001"], f"{list((out / 'runs').iterdir())}")
    check(not (out / "runs" / "0000" / ".sesi-sweep-staging").exists(), "a run directory kept the staging marker")
    check([r["status"] for r in rows(out)] == ["ok", "ok"], f"{rows(out)}")


def lennard_jones_scene(n, seed=1, density=0.5, speed=1.0):
    """n Lennard-Jones bodies on S^2 as tools/lattice_scene.py makes them (a Fibonacci lattice at
    the given density, random tangent velocities), 2 threads, the trajectory every 10 steps."""
    rng = random.Random(seed)
    radius = math.sqrt(n / (4 * math.pi * density))
    golden = math.pi * (3 - math.sqrt(5))
    lines = [f'name = "lj-s2-{n}"', "[space]", 'kind = "sphere"', "dim = 2", f"radius = {radius!r}"]
    for k in range(n):
        z = 1 - 2 * (k + 0.5) / n
        rho = math.sqrt(1 - z * z)
        x = [radius * rho * math.cos(k * golden), radius * rho * math.sin(k * golden), radius * z]
        v = [rng.gauss(0, speed) for _ in range(3)]
        dot = sum(xi * vi for xi, vi in zip(x, v)) / radius ** 2
        v = [vi - dot * xi for xi, vi in zip(x, v)]
        lines += ["[[bodies]]", "mass = 1.0", f"x = [{x[0]!r}, {x[1]!r}, {x[2]!r}]", f"v = [{v[0]!r}, {v[1]!r}, {v[2]!r}]"]
    lines += ["[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5",
              "[integrator]", 'method = "sesi2"', "dt = 0.005", "t_end = 0.2", "output_every = 10", "threads = 2", ""]
    return "\n".join(lines)


def summary_without_timing(path):
    data = json.loads(path.read_text())
    return {k: v for k, v in data.items() if k != "wall_seconds" and "thread" not in k}


@case
def sweep_threads_same_as_one_thread(ctx):
    """Runs of 2000 Lennard-Jones bodies on S^2 with threads = 2 (the scene's key, which the sweep
    keeps): every output equals, byte for byte (cmp), sesi run of the same scene with --threads 1,
    across Verlet-list rebuilds."""
    import filecmp
    ctx.write("lj.toml", lennard_jones_scene(2000))
    sweep = ctx.write("sweep.toml", """scene = "lj.toml"
trajectory = true
[[vary]]
key = "integrator.dt"
values = [0.005, 0.004]
""")
    out = ctx.work / "out"
    expect_status(ctx.run("sweep", sweep, "--out", out, "--jobs", "1", "-q"), 0, "sesi sweep (2 threads a run)")
    runs = run_dirs(out)
    check(len(runs) == 2, f"runs: {runs}")
    half_skin = 0.5 * 0.12 * 2.5  # the lists are rebuilt once a body has moved half the skin (0.12 of the cutoff)
    for run in runs:
        check("threads = 2" in (run / "scene.toml").read_text(), f"{run}: the variant lost threads = 2")
        reference = ctx.work / "one-thread" / run.name
        expect_status(ctx.run("run", "scene.toml", "--threads", "1", "--out", reference, "-q", cwd=run), 0,
                      f"sesi run {run.name} --threads 1")
        names = sorted(p.name for p in reference.iterdir() if p.name != "summary.json")
        check("trajectory.csv" in names and "diagnostics.csv" in names, f"{reference}: {names}")
        for name in names:
            check(filecmp.cmp(run / name, reference / name, shallow=False),
                  f"run {run.name}: {name} with 2 threads differs from --threads 1")
        check(summary_without_timing(run / "summary.json") == summary_without_timing(reference / "summary.json"),
              f"run {run.name}: summary.json with 2 threads differs from --threads 1")
        used = json.loads((run / "summary.json").read_text()).get("threads_used", 2)
        check(used == 2, f"run {run.name} used {used} threads, not the scene's 2")
        # A rebuild happened: some body ended farther than half the skin (chord <= arc) from its start.
        with open(run / "trajectory.csv", newline="") as f:
            table = list(csv.reader(f))
        header, first, last = table[0], table[1], table[-1]
        check(first[0] != last[0], f"run {run.name}: one frame in trajectory.csv")
        moved = 0.0
        for i, column in enumerate(header):
            if column.endswith("_x1"):  # b7_x1, b7_x2, b7_x3: body 7's embedding point
                chord = math.dist([float(first[i + k]) for k in range(3)], [float(last[i + k]) for k in range(3)])
                moved = max(moved, chord)
        check(moved > half_skin, f"run {run.name}: bodies moved at most {moved}, no Verlet-list rebuild")


def box_scene(seed=2):
    """20 Lennard-Jones bodies on a 5 x 4 lattice in a periodic 6 x 5 box of E^2 (issue #26), drifting
    at (1.5, -1) with random velocities of deviation 0.5 about it: by t = 1 the outer columns and rows
    (0.6 from a face) have crossed it, so the image counts change."""
    rng = random.Random(seed)
    lines = ['name = "lj-box"', "[space]", 'kind = "euclidean"', "dim = 2", "box = [6.0, 5.0]"]
    for i in range(5):
        for j in range(4):
            lines += ["[[bodies]]", "mass = 1.0", f"x = [{0.6 + 1.2 * i!r}, {0.625 + 1.25 * j!r}]",
                      f"v = [{1.5 + rng.gauss(0, 0.5)!r}, {-1.0 + rng.gauss(0, 0.5)!r}]"]
    lines += ["[[potential]]", 'kind = "lennard-jones"', "sigma = 0.5", "cutoff = 1.25",
              "[integrator]", 'method = "sesi4"', "dt = 0.005", "t_end = 1.0", "output_every = 20", ""]
    return "\n".join(lines)


def surface_scene():
    """8 bodies on the genus-2 surface of radius 2 (issue #26), leaving the octagon through its sides
    (they start 2.9 from its centre, moving outwards at unit speed; the inradius is 3.06)."""
    radius = 2.0
    lines = ['name = "genus"', "[space]", 'kind = "hyperbolic"', "dim = 2", f"radius = {radius!r}", "genus = 2"]
    for k in range(8):
        phi, d = 2 * math.pi * (k + 0.3) / 8, 2.9 / radius
        x = [radius * math.sinh(d) * math.cos(phi), radius * math.sinh(d) * math.sin(phi), radius * math.cosh(d)]
        v = [math.cosh(d) * math.cos(phi), math.cosh(d) * math.sin(phi), math.sinh(d)]
        lines += ["[[bodies]]", "mass = 1.0", "x = [" + ", ".join(map(repr, x)) + "]",
                  "v = [" + ", ".join(map(repr, v)) + "]"]
    lines += ["[[potential]]", 'kind = "lennard-jones"', "sigma = 0.5", "cutoff = 1.25",
              "[integrator]", 'method = "sesi4"', "dt = 0.005", "t_end = 0.5", "output_every = 10", ""]
    return "\n".join(lines)


@case
def sweep_topology_keys(ctx):
    """space.box and space.genus vary like any scene key (issue #26): each run's summary says its box or
    genus, a larger box is a lower density, and a value the scene reader refuses (an edge that makes the
    cutoff too long, genus 1) ends the sweep before anything runs, naming the run."""
    ctx.write("box.toml", box_scene())
    ctx.write("surface.toml", surface_scene())
    box = ctx.write("box-sweep.toml", 'scene = "box.toml"\ntrajectory = true\n[[vary]]\nkey = "space.box"\n'
                                      "values = [[6.0, 5.0], [8.0, 7.5]]\n")
    out = ctx.work / "out-box"
    expect_status(ctx.run("sweep", box, "--out", out, "-q"), 0, "sesi sweep over space.box")
    table = rows(out)
    check([(float(r["space.box.0"]), float(r["space.box.1"]), r["status"]) for r in table] ==
          [(6.0, 5.0, "ok"), (8.0, 7.5, "ok")], f"sweep.csv: {table}")
    for row, run in zip(table, run_dirs(out)):
        space = json.loads((run / "summary.json").read_text())["space"]
        check(space.get("box") == [float(row["space.box.0"]), float(row["space.box.1"])], f"{run.name}: {space}")
        # The cutoff check's bound: half the shortest edge.
        check(space.get("max_cutoff") == min(space["box"]) / 2, f"{run.name}: {space}")
    expect_same_as_sesi_run(ctx, out)
    surface = ctx.write("genus-sweep.toml", 'scene = "surface.toml"\ntrajectory = true\n[[vary]]\n'
                                            'key = "space.genus"\nvalues = [2, 3]\n')
    out = ctx.work / "out-genus"
    expect_status(ctx.run("sweep", surface, "--out", out, "-q"), 0, "sesi sweep over space.genus")
    cutoffs = []
    for row, run in zip(rows(out), run_dirs(out)):
        space = json.loads((run / "summary.json").read_text())["space"]
        check(row["status"] == "ok" and space.get("genus") == int(row["space.genus"]), f"{run.name}: {row} {space}")
        cutoffs.append(space["max_cutoff"])
        header = (run / "trajectory.csv").read_text().splitlines()[0].split(",")
        check("b1_word" in header and "b1_u3" in header, f"{run.name}: no word columns: {header}")
    # At the same radius a larger genus has a larger polygon (inradius arccosh(cot(pi / 4g)) R).
    check(cutoffs[0] < cutoffs[1], f"max_cutoff over genus 2, 3: {cutoffs}")
    expect_same_as_sesi_run(ctx, out)
    for name, sweep, message in (
            ("edge", 'scene = "box.toml"\n[[vary]]\nkey = "space.box.1"\nvalues = [5.0, 2.0]\n', "run 0001"),
            ("genus", 'scene = "surface.toml"\n[[vary]]\nkey = "space.genus"\nvalues = [2, 1]\n', "run 0001")):
        path = ctx.write(f"bad-{name}.toml", sweep)
        bad = ctx.work / f"out-bad-{name}"
        expect_input_error(ctx.run("sweep", path, "--out", bad), message)
        check(not bad.exists(), f"{name}: a refused sweep wrote {bad}")


@case
def sweep_mpi_box(ctx):
    """A sweep of a periodic box's edges (issue #26) on 1 and 2 ranks: the same files (trajectories with
    the image counts included), each as sesi run writes it."""
    if not ctx.mpiexec:
        raise Skip("sesi is built without MPI (SESI_BUILD_MPI, libopenmpi-dev)")
    ctx.write("box.toml", box_scene())
    sweep = ctx.write("box-sweep.toml", 'scene = "box.toml"\ntrajectory = true\n[[vary]]\nkey = "space.box"\n'
                                        "values = [[6.0, 5.0], [7.0, 6.0]]\n")
    trees = []
    for ranks in (1, 2):
        out = ctx.work / f"out-box-np{ranks}"
        expect_status(ctx.run("sweep", sweep, "--out", out, ranks=ranks), 0, f"mpiexec -np {ranks} sesi sweep")
        trees.append(file_tree(out))
        if ranks == 2:
            expect_same_as_sesi_run(ctx, out)
    check(trees[0] == trees[1], "a box sweep's outputs depend on the number of ranks")
    # Bodies crossed faces: some image count in the trajectories is not 0.
    crossed = False
    for name, data in trees[0][0].items():
        if name.endswith("trajectory.csv"):
            table = list(csv.reader(data.decode().splitlines()))
            counts = [i for i, column in enumerate(table[0]) if re.fullmatch(r"b\d+_n\d", column)]
            check(counts, f"{name}: no image-count columns in {table[0][:8]}")
            crossed = crossed or any(row[i] != "0" for row in table[1:] for i in counts)
    check(crossed, "no body crossed a face of the box: the sweep tests no image counts")


LONG = 10_000_000  # the 10 MB


@case
def sweep_long_input_cut(ctx):
    """A 10 MB key or value in a sweep file: one line on stderr quoting 80 bytes of it and its size."""
    ctx.scene("sphere-two-body-xv.toml", t_end=0.5)
    k = "k" * LONG
    sweeps = {
        "top_key": f'scene = "sphere-two-body-xv.toml"\n{k} = 1\n[[vary]]\nkey = "integrator.dt"\nvalues = [0.1]\n',
        "vary_key": f'scene = "sphere-two-body-xv.toml"\n[[vary]]\nkey = "{k}"\nvalues = [0.1]\n',
        "value": f'scene = "sphere-two-body-xv.toml"\n[[vary]]\nkey = "integrator.method"\nvalues = ["{k}"]\n',
        "index": f'scene = "sphere-two-body-xv.toml"\n[[vary]]\nkey = "bodies.{k}.x"\nperturb = 1e-6\ncount = 2\n',
    }
    cut = "k" * 80 + f"... ({LONG} bytes)"
    for name, text in sweeps.items():
        short = ctx.run("sweep", ctx.write(f"{name}.toml", text.replace(k, "k" * 10)), "--out", ctx.work / "out")
        path = ctx.write(f"{name}.toml", text)
        result = ctx.run("sweep", path, "--out", ctx.work / "out")
        err = result.stderr
        shown = err if len(err) < 1000 else err[:300] + f"... ({len(err)} bytes)"
        # The same message as for a 10-byte piece, the piece (quoted at most twice: in the run's
        # values and in the scene reader's message) now 80 bytes and "... (10000000 bytes)".
        check(len(err) <= len(short.stderr) + 2 * (80 + 20 - 10), f"{name}: {len(err)} bytes on stderr: {shown!r}")
        try:
            expect_input_error(result, cut)
        except Failure as e:
            raise Failure(f"{name}: {e}")
        check(not (ctx.work / "out").exists(), f"{name}: outputs were written")
        path.unlink()


# ---- driver ------------------------------------------------------------------------------------

def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--list", action="store_true")
    parser.add_argument("--sesi")
    parser.add_argument("--source", default=str(pathlib.Path(__file__).resolve().parent.parent.parent))
    parser.add_argument("--work")
    parser.add_argument("--case")
    parser.add_argument("--mpiexec", default="")
    args = parser.parse_args()
    if args.list:
        print("\n".join(sorted(CASES)))
        return 0
    work = pathlib.Path(args.work) / args.case
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    ctx = Context(args.sesi, args.source, work, args.mpiexec)
    try:
        CASES[args.case](ctx)
    except (Skip, Failure) as e:
        skipped = isinstance(e, Skip)
        print(f"{'SKIPPED' if skipped else 'FAILED ' + args.case}: {e}")
        return SKIP if skipped else 1
    print(f"passed {args.case}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
