#!/usr/bin/env python3
"""Tests of the `sesi` program, one ctest test per case (tests/program/CMakeLists.txt).

    check_program.py --list
    check_program.py --sesi PATH --source REPO --work DIR --case NAME

Cases come from three places: the functions marked @case below, the bad scenes in bad/*.toml
(case bad_<stem>; each file's header says which key, line and message sesi must report), and
the example scenes in examples/scenes/*.toml (case example_<stem>). Standard library only.
Exit status 0 passes, 77 skips (ctest SKIP_RETURN_CODE), anything else fails.
"""
import argparse
import json
import math
import os
import pathlib
import pty
import select
import shutil
import signal
import subprocess
import sys
import time

HERE = pathlib.Path(__file__).resolve().parent
SKIP = 77
METHODS = {"sesi2": 2, "sesi4": 4, "sesi4-suzuki": 4, "sesi4-mclachlan": 4, "sesi6": 6,
           "sesi6-kahan-li": 6, "sesi8": 8, "sesi8-kahan-li": 8}
POTENTIALS = ["chord-well", "cotangent-gravity", "central-cotangent", "harmonic-pair", "lennard-jones"]
OUTPUTS = ["trajectory.csv", "diagnostics.csv", "summary.json"]

CASES = {}


def case(function):
    CASES[function.__name__] = function
    return function


class Failure(Exception):
    pass


class Skip(Exception):
    pass


def check(condition, message):
    if not condition:
        raise Failure(message)


# ---- running sesi ------------------------------------------------------------------------------

class Context:
    def __init__(self, sesi, source, work):
        self.sesi = sesi
        self.source = pathlib.Path(source)
        self.work = pathlib.Path(work)

    def run(self, *args, cwd=None, timeout=300):
        return subprocess.run([self.sesi, *map(str, args)], cwd=cwd or self.work, capture_output=True,
                              text=True, timeout=timeout, stdin=subprocess.DEVNULL)

    def scene(self, name):
        return self.source / "examples" / "scenes" / name

    def write(self, name, text):
        path = self.work / name
        path.write_text(text)
        return path


def read_csv(path):
    lines = pathlib.Path(path).read_text().splitlines()
    return lines[0].split(","), [[float(v) for v in line.split(",")] for line in lines[1:]]


def summary(directory):
    return json.loads((pathlib.Path(directory) / "summary.json").read_text())


def expect_ok(result, what):
    check(result.returncode == 0,
          f"{what}: exit status {result.returncode}, stderr: {result.stderr.strip()}")
    check(result.stderr == "", f"{what}: unexpected stderr: {result.stderr!r}")


def expect_input_error(result, *, file=None, line=0, key="", text=""):
    """Exit status 2, nothing on stdout, one line on stderr naming file, line, key and text."""
    err = result.stderr
    check(result.returncode == 2, f"exit status {result.returncode}, expected 2; stderr: {err!r}")
    check(result.stdout == "", f"stdout should be empty, got {result.stdout!r}")
    check(err.endswith("\n") and err.count("\n") == 1, f"expected one line on stderr, got {err!r}")
    check(err.startswith("sesi: error: "), f"stderr does not start with 'sesi: error: ': {err!r}")
    check("Traceback" not in err and "terminate called" not in err, f"crash on stderr: {err!r}")
    if file:
        check(str(file) in err, f"stderr does not name the file {file}: {err!r}")
    if file and line:
        check(f"{file}:{line}:" in err, f"stderr does not name line {line}: {err!r}")
    if key:
        check(f" {key}: " in err, f"stderr does not name the key {key!r}: {err!r}")
    if text:
        check(text in err, f"stderr does not say {text!r}: {err!r}")


# ---- an output directory holding an earlier run, which bad input must leave alone ---------------

def earlier_outputs(directory):
    directory = pathlib.Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    for name in OUTPUTS:
        (directory / name).write_text(f"earlier {name}\n")
    (directory / "plot.png").write_bytes(b"earlier plot")
    return snapshot(directory)


def snapshot(directory):
    directory = pathlib.Path(directory)
    state = {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted(directory.iterdir())}
    state["<dir mtime>"] = directory.stat().st_mtime_ns
    return state


def expect_untouched(directory, before):
    directory = pathlib.Path(directory)
    check(directory.is_dir(), f"{directory} was removed")
    check(snapshot(directory) == before, f"{directory} was changed")
    expect_no_staging_left(directory)


def expect_no_staging_left(directory):
    directory = pathlib.Path(directory)
    leftovers = [p.name for p in directory.parent.iterdir() if p.name.startswith(f".{directory.name}.sesi-")]
    check(not leftovers, f"staging directories left behind: {leftovers}")


# ---- bad scenes (bad/*.toml) -------------------------------------------------------------------

def bad_scene_expectations(path):
    expect = {"key": "", "text": "", "line": 0}
    for line in path.read_text().splitlines():
        if line.startswith("# expect-"):
            name, _, value = line[len("# expect-"):].partition(":")
            expect[name] = value.strip()
    expect["line"] = int(expect["line"] or 0)
    return expect


def run_bad_scene(ctx, stem):
    path = HERE / "bad" / f"{stem}.toml"
    expect = bad_scene_expectations(path)
    out = ctx.work / "out"
    before = earlier_outputs(out)
    result = ctx.run("run", path, "--out", out)
    expect_input_error(result, file=path, line=expect["line"], key=expect["key"], text=expect["text"])
    expect_untouched(out, before)


# ---- command-line arguments and the output directory ----------------------------------------------

def arg_error(ctx, args, key, text):
    out = ctx.work / "out"
    before = earlier_outputs(out)
    result = ctx.run("run", *args, "--out", out)
    expect_input_error(result, key=key, text=text)
    expect_untouched(out, before)


@case
def args_dt_zero(ctx):
    arg_error(ctx, ["--dt", "0"], "--dt", "expected a finite, non-zero step")


@case
def args_dt_nan(ctx):
    arg_error(ctx, ["--dt", "nan"], "--dt", "got nan")


@case
def args_dt_inf(ctx):
    arg_error(ctx, ["--dt", "inf"], "--dt", "got inf")


@case
def args_dt_not_a_number(ctx):
    arg_error(ctx, ["--dt", "abc"], "", "--dt")


@case
def args_t_end_negative(ctx):
    arg_error(ctx, ["--t-end", "-1"], "--t-end", "expected a finite end time >= 0")


@case
def args_t_end_nan(ctx):
    arg_error(ctx, ["--t-end", "nan"], "--t-end", "got nan")


@case
def args_too_many_steps(ctx):
    arg_error(ctx, ["--dt", "1e-300"], "--dt/--t-end", "at most")


@case
def args_method_unknown(ctx):
    arg_error(ctx, ["--method", "sesi4-mclachan"], "--method", "did you mean 'sesi4-mclachlan'?")


@case
def args_output_every_zero(ctx):
    arg_error(ctx, ["--output-every", "0"], "--output-every", "expected an integer >= 1")


@case
def args_unknown_option(ctx):
    arg_error(ctx, ["--bogus"], "", "--bogus")


@case
def args_extra_positional(ctx):
    scene = ctx.scene("paper.toml")
    arg_error(ctx, [scene, scene], "", "not expected")


@case
def args_scene_missing(ctx):
    arg_error(ctx, [ctx.work / "no-such-scene.toml"], "", "cannot read the scene file")


@case
def args_scene_is_directory(ctx):
    arg_error(ctx, [ctx.work], "", "got a directory")


@case
def args_no_subcommand(ctx):
    result = ctx.run()
    expect_input_error(result, text="subcommand")


@case
def out_parent_is_a_file(ctx):
    blocker = ctx.write("blocker", "a file where a directory should be\n")
    result = ctx.run("run", "--t-end", "1", "--out", blocker / "sub")
    expect_input_error(result, key=f"--out {blocker / 'sub'}", text="cannot create the parent directory")
    check(blocker.read_text() == "a file where a directory should be\n", "the blocking file changed")


@case
def out_is_a_file(ctx):
    target = ctx.write("target", "not a directory\n")
    result = ctx.run("run", "--t-end", "1", "--out", target)
    expect_input_error(result, key=f"--out {target}", text="not a directory")
    check(target.read_text() == "not a directory\n", "the file changed")


@case
def out_holds_other_files(ctx):
    out = ctx.work / "out"
    earlier_outputs(out)
    (out / "notes.txt").write_text("mine\n")
    before = snapshot(out)
    result = ctx.run("run", "--t-end", "1", "--out", out)
    expect_input_error(result, key=f"--out {out}", text="'notes.txt', which sesi did not write")
    expect_untouched(out, before)


@case
def out_unwritable(ctx):
    if os.geteuid() == 0:
        # Root ignores directory permissions, but not sysfs's: nothing may be created there.
        out = pathlib.Path("/sys/sesi-out-test")
        if not pathlib.Path("/sys").is_dir() or out.exists():
            raise Skip("no sysfs to stand for an unwritable directory")
        result = ctx.run("run", "--t-end", "1", "--out", out)
        expect_input_error(result, key=f"--out {out}", text="cannot write")
        check(not out.exists(), f"{out} was created")
        return
    parent = ctx.work / "locked"
    parent.mkdir()
    out = parent / "out"
    before = earlier_outputs(out)
    parent.chmod(0o555)
    try:
        result = ctx.run("run", "--t-end", "1", "--out", out)
    finally:
        parent.chmod(0o755)
    expect_input_error(result, key=f"--out {out}", text="cannot write")
    expect_untouched(out, before)


# ---- the default scene -------------------------------------------------------------------------

REQUIRED_SUMMARY = {
    "method": str, "dt": float, "steps": int, "t_end": float, "wall_seconds": float, "complete": bool,
    "energy": {"initial": float, "final": float, "max_abs_error": float, "max_rel_error": float},
    "momentum_map": {"initial": list, "final": list, "max_abs_drift": float},
    "final_state": {"t": float, "bodies": list},
}


def expect_fields(data, schema, where="summary.json"):
    for key, kind in schema.items():
        check(key in data, f"{where} lacks {key!r}")
        if isinstance(kind, dict):
            expect_fields(data[key], kind, f"{where}.{key}")
        elif kind is float:
            check(isinstance(data[key], (int, float)) and not isinstance(data[key], bool),
                  f"{where}.{key} is not a number: {data[key]!r}")
        else:
            check(isinstance(data[key], kind), f"{where}.{key} is not a {kind.__name__}: {data[key]!r}")


@case
def default_scene(ctx):
    out = ctx.work / "paper"
    result = ctx.run("run", "--out", out)
    expect_ok(result, "sesi run")
    check("sesi4" in result.stdout and "8000 steps" in result.stdout, f"report: {result.stdout!r}")
    for name in OUTPUTS + ["exact.csv"]:
        check((out / name).is_file(), f"{name} missing")
    expect_no_staging_left(out)
    s = summary(out)
    expect_fields(s, REQUIRED_SUMMARY)
    check(s["complete"] is True and s["method"] == "sesi4" and s["steps"] == 8000, f"summary: {s}")
    check(s["dt"] == 0.1 and s["t_end"] == 800 and s["final_state"]["t"] == 800, "dt, t_end, final t")
    check('"dt": 0.10000000000000001' in (out / "summary.json").read_text(), "numbers not printed with %.17g")
    # The seed's energy (shared/paper-scene.md gives 15 digits).
    check(abs(s["energy"]["initial"] - 0.183243903882068) < 1e-15, f"initial energy {s['energy']['initial']}")
    for body in s["final_state"]["bodies"]:
        check(set(body) >= {"q", "p", "x", "v"} and len(body["q"]) == 2 and len(body["x"]) == 3, f"body {body}")

    header, rows = read_csv(out / "trajectory.csv")
    check(header[:8] == ["t", "b1_q1", "b1_q2", "b1_p1", "b1_p2", "b1_x1", "b1_x2", "b1_x3"], f"header {header}")
    check(len(header) == 1 + 3 * 7 and len(rows) == 8001, f"trajectory shape {len(header)} x {len(rows)}")
    first = rows[0]
    for b in range(3):
        q1, q2, p1, p2 = first[1 + 7 * b: 5 + 7 * b]
        check(q1 == math.pi / 4 and abs(q2 - 2 * math.pi * b / 3) < 1e-15 and p1 == 0.25
              and p2 == 0.1727174029854043, f"initial state of body {b + 1}: {first[1 + 7 * b: 5 + 7 * b]}")
    last_x = rows[-1][5:8]
    check(last_x == s["final_state"]["bodies"][0]["x"], "final x differs between summary and trajectory")

    # Every step is a row here, so the summary's maxima must be the maxima over the rows.
    dheader, drows = read_csv(out / "diagnostics.csv")
    check(dheader == ["t", "energy", "energy_error", "M1_2", "M1_3", "M2_3"], f"diagnostics header {dheader}")
    max_error = max(abs(r[2]) for r in drows)
    check(max_error == s["energy"]["max_abs_error"], f"max energy error {max_error} vs {s['energy']['max_abs_error']}")
    check(drows[0][3:] == s["momentum_map"]["initial"] and drows[-1][3:] == s["momentum_map"]["final"],
          "momentum map in summary and diagnostics differ")
    drift = max(abs(r[k] - drows[0][k]) for r in drows for k in range(3, 6))
    check(drift == s["momentum_map"]["max_abs_drift"], "momentum drift in summary and diagnostics differ")

    eheader, erows = read_csv(out / "exact.csv")
    check(len(erows) == len(rows) and eheader[0] == "t", "exact.csv shape")
    worst = max(math.dist(r[5:8], e[1:4]) for r, e in zip(rows, erows))
    check(abs(worst - s["exact"]["max_position_error"][0]) <= 1e-15, "exact position error inconsistent")


@case
def default_out_dir(ctx):
    result = ctx.run("run", "--t-end", "1", "--quiet", cwd=ctx.work)
    expect_ok(result, "sesi run --quiet")
    check(result.stdout == "", f"--quiet printed {result.stdout!r}")
    check((ctx.work / "sesi-out" / "paper" / "summary.json").is_file(), "./sesi-out/paper not written")


@case
def default_equals_paper_file(ctx):
    ctx.run("run", "--t-end", "20", "--out", ctx.work / "a", "-q")
    expect_ok(ctx.run("run", ctx.scene("paper.toml"), "--t-end", "20", "--out", ctx.work / "b", "-q"), "paper.toml")
    for name in ["trajectory.csv", "diagnostics.csv", "exact.csv"]:
        check((ctx.work / "a" / name).read_bytes() == (ctx.work / "b" / name).read_bytes(),
              f"{name}: the embedded scene and examples/scenes/paper.toml differ")


@case
def reproducible(ctx):
    # -ffp-contract=off and no -ffast-math: the same scene gives bit-identical numbers on one machine.
    for scene in ["paper.toml", "sphere-pole-crossing.toml", "hyperbolic-kepler-xv.toml"]:
        runs = []
        for k in range(2):
            out = ctx.work / f"repro-{scene}-{k}"
            expect_ok(ctx.run("run", ctx.scene(scene), "--t-end", "20", "--quiet", "--out", out), scene)
            data = summary(out)
            data.pop("wall_seconds")
            runs.append((data, (out / "trajectory.csv").read_bytes(), (out / "diagnostics.csv").read_bytes()))
        check(runs[0] == runs[1], f"two runs of {scene} differ")


@case
def replaces_earlier_outputs(ctx):
    out = ctx.work / "out"
    earlier_outputs(out)
    expect_ok(ctx.run("run", "--t-end", "1", "--out", out, "-q"), "sesi run")
    check(summary(out)["complete"] is True, "summary not replaced")
    check(not (out / "plot.png").exists(), "the earlier run's files should go with it")
    expect_no_staging_left(out)


@case
def help_texts(ctx):
    top = ctx.run("--help")
    check(top.returncode == 0 and "run" in top.stdout, f"sesi --help: {top.returncode} {top.stdout!r}")
    run = ctx.run("run", "--help")
    check(run.returncode == 0, f"sesi run --help: {run.returncode}")
    for word in [*METHODS, *POTENTIALS, "--out", "--method", "--dt", "--t-end", "--quiet", "trajectory.csv",
                 "diagnostics.csv", "summary.json", "EXIT STATUS"]:
        check(word in run.stdout, f"sesi run --help does not mention {word}")
    version = ctx.run("--version")
    check(version.returncode == 0 and version.stdout.startswith("sesi "), f"--version: {version.stdout!r}")


# ---- scenes given two ways, methods, dimensions ---------------------------------------------------

def same_trajectories(a, b, tolerance):
    ha, ra = read_csv(a)
    hb, rb = read_csv(b)
    check(ha == hb and len(ra) == len(rb), "different headers or row counts")
    worst = max(abs(x - y) / (1 + abs(x)) for r, s in zip(ra, rb) for x, y in zip(r, s))
    check(worst <= tolerance, f"trajectories differ by {worst:.3g} > {tolerance:.3g}")


def qp_equals_xv(ctx, name):
    # The files give one state two ways; the conversion x, v -> q, p is exact to round-off, which
    # the dynamics amplify only slowly over t = 1.
    for form in ["qp", "xv"]:
        expect_ok(ctx.run("run", ctx.scene(f"{name}-{form}.toml"), "--t-end", "1", "--out", ctx.work / form, "-q"),
                  form)
    same_trajectories(ctx.work / "qp" / "trajectory.csv", ctx.work / "xv" / "trajectory.csv", 1e-12)


@case
def qp_equals_xv_sphere(ctx):
    qp_equals_xv(ctx, "sphere-two-body")


@case
def qp_equals_xv_hyperbolic(ctx):
    qp_equals_xv(ctx, "hyperbolic-kepler")


@case
def qp_equals_xv_euclidean(ctx):
    qp_equals_xv(ctx, "euclidean-figure-eight")


@case
def method_orders(ctx):
    """Each name runs a method of the stated order: final states at steps h, h/2, h/4 (paper scene,
    t = 10) differ by C h^p (1 + O(h^2)) for these symmetric methods, so the observed order
    log2(e(h)/e(h/2)) is p up to O(h^2); 0.3 leaves room for that at h = 0.2. At order 8 the next
    term is large in the kick-drift-kick form the program runs on S^2 (docs/scheme.md): sesi8
    (McLachlan's SS15) measures 8.75 here and 8.07 at h = 0.1, so order 8 gets 0.8, which
    still tells 8 from 6 and 10."""
    for method, order in METHODS.items():
        states = []
        for h in [0.2, 0.1, 0.05]:
            out = ctx.work / f"{method}-{h}"
            expect_ok(ctx.run("run", "--method", method, "--dt", h, "--t-end", "10", "--output-every", "1000",
                              "--out", out, "-q"), method)
            s = summary(out)
            check(s["method"] == method, f"summary names {s['method']}")
            states.append([c for b in s["final_state"]["bodies"] for c in b["q"] + b["p"]])
        e1, e2 = math.dist(states[0], states[1]), math.dist(states[1], states[2])
        observed = math.log2(e1 / e2)
        tolerance = 0.8 if order == 8 else 0.3
        check(abs(observed - order) < tolerance, f"{method}: observed order {observed:.2f}, expected {order}")


def embedded_scene(kind, dim, bodies, potentials, t_end):
    lines = [f'name = "{kind}{dim}"', "[space]", f'kind = "{kind}"', f"dim = {dim}"]
    for x, v in bodies:
        lines += ["[[bodies]]", "mass = 1.0", f"x = {list(x)}", f"v = {list(v)}"]
    lines += potentials
    lines += ["[integrator]", 'method = "sesi4"', "dt = 0.01", f"t_end = {t_end}"]
    return "\n".join(lines) + "\n"


def dimensions(ctx, kind, bodies2, potentials, lift):
    """The same motion on a totally geodesic 2-dimensional subspace of spaces of dimension 2..10
    (fixed-size charts up to 8, Eigen::Dynamic above): the embedding points must agree with the
    2-dimensional run to round-off (amplified over t = 1). Dimension 1 must run."""
    ambient2 = len(bodies2[0][0])
    runs = {}
    for dim in range(2, 11):
        bodies = [(lift(x, dim), lift(v, dim)) for x, v in bodies2]
        path = ctx.write(f"{kind}{dim}.toml", embedded_scene(kind, dim, bodies, [p(dim) for p in potentials], 1.0))
        out = ctx.work / f"out{dim}"
        expect_ok(ctx.run("run", path, "--out", out, "-q"), f"{kind} dim {dim}")
        header, rows = read_csv(out / "trajectory.csv")
        runs[dim] = (header, rows)
    reference = runs[2][1]
    for dim in range(3, 11):
        header, rows = runs[dim]
        check(len(rows) == len(reference), f"dim {dim}: {len(rows)} rows")
        for b in range(len(bodies2)):
            ref_cols = [runs[2][0].index(f"b{b + 1}_x{a + 1}") for a in range(ambient2)]
            cols = [header.index(f"b{b + 1}_x{a + 1}") for a in lift_index(kind, dim)]
            worst = max(abs(r[c] - s[k]) for r, s in zip(rows, reference) for c, k in zip(cols, ref_cols))
            check(worst < 1e-12, f"{kind} dim {dim}, body {b + 1}: x differs from dim 2 by {worst:.3g}")
    # Dimension 1: the circle, the hyperbolic line, the line.
    one = {"sphere": [([1.0, 0.0], [0.0, 0.5]), ([0.0, 1.0], [-0.3, 0.0])],
           "hyperbolic": [([3.626860407847019, 3.7621956910836314], [1.1286587073250893, 1.0880581223541057]),
                          ([-1.1752011936438014, 1.5430806348152437], [0.0, 0.0])],
           "euclidean": [([0.0], [0.5]), ([1.5], [0.0])]}[kind]
    path = ctx.write(f"{kind}1.toml", embedded_scene(kind, 1, one, [p(1) for p in potentials], 1.0))
    expect_ok(ctx.run("run", path, "--out", ctx.work / "out1", "-q"), f"{kind} dim 1")


def lift_index(kind, dim):
    """Where the coordinates of the 2-dimensional subspace sit in dimension dim."""
    if kind == "hyperbolic":
        return [0, 1, dim]  # (x1, x2, 0, ..., 0, x_time)
    return list(range(3 if kind == "sphere" else 2))


def lifter(kind):
    def lift(x, dim):
        x = list(x)
        if kind == "sphere":
            return x + [0.0] * (dim - 2)
        if kind == "hyperbolic":
            return x[:2] + [0.0] * (dim - 2) + [x[2]]
        return x + [0.0] * (dim - 2)
    return lift


@case
def dimensions_sphere(ctx):
    bodies = [([0.9320390859672263, 0.0, 0.3623577544766736], [0.0, 0.4291665510839589, 0.0]),
              ([0.9463000876874145, 0.0, -0.32328956686350335], [0.0, -0.4226988935164609, 0.0])]
    potentials = [lambda dim: '[[potential]]\nkind = "cotangent-gravity"\nG = 1.0']
    dimensions(ctx, "sphere", bodies, potentials, lifter("sphere"))


@case
def dimensions_hyperbolic(ctx):
    bodies = [([0.888105982187623, 0.0, 1.3374349463048447], [0.0, 0.6755950438730891, 0.0]),
              ([-1.5256189899643362, 1.1396714025940833, 2.1508984653931407],
               [-0.8474738575766381, -0.41567277560476557, 0.3808603002903068])]
    potentials = [lambda dim: '[[potential]]\nkind = "central-cotangent"\ncenter = '
                  + str([0.0] * dim + [1.0]),
                  lambda dim: '[[potential]]\nkind = "cotangent-gravity"\nG = 0.1']
    dimensions(ctx, "hyperbolic", bodies, potentials, lifter("hyperbolic"))


@case
def dimensions_euclidean(ctx):
    bodies = [([0.97000436, -0.24308753], [0.466203685, 0.43236573]),
              ([-0.97000436, 0.24308753], [0.466203685, 0.43236573]),
              ([0.0, 0.0], [-0.93240737, -0.86473146])]
    potentials = [lambda dim: '[[potential]]\nkind = "cotangent-gravity"\nG = 1.0',
                  lambda dim: '[[potential]]\nkind = "harmonic-pair"\nk = 0.1\nd0 = 1.0']
    dimensions(ctx, "euclidean", bodies, potentials, lifter("euclidean"))


# ---- the time grid -----------------------------------------------------------------------------

@case
def output_every(ctx):
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "10", "--output-every", "7", "--out", out, "-q"), "run")
    _, rows = read_csv(out / "trajectory.csv")
    times = [r[0] for r in rows]
    expected = [k * 0.1 for k in range(0, 100, 7)] + [10.0]
    check(len(times) == len(expected) and all(abs(a - b) < 1e-12 for a, b in zip(times, expected)),
          f"row times {times}")
    _, drows = read_csv(out / "diagnostics.csv")
    check([r[0] for r in drows] == times, "diagnostics rows differ from trajectory rows")


@case
def partial_last_step(ctx):
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--dt", "0.3", "--t-end", "1", "--out", out, "-q"), "run")
    s = summary(out)
    _, rows = read_csv(out / "trajectory.csv")
    check(s["steps"] == 4 and s["final_state"]["t"] == 1.0, f"steps {s['steps']}, final t {s['final_state']['t']}")
    check([r[0] for r in rows] == [0.0, 0.3, 0.6, 0.8999999999999999, 1.0] or
          all(abs(a - b) < 1e-15 for a, b in zip([r[0] for r in rows], [0, 0.3, 0.6, 0.9, 1.0])),
          f"row times {[r[0] for r in rows]}")


@case
def t_end_zero(ctx):
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "0", "--out", out, "-q"), "run")
    s = summary(out)
    _, rows = read_csv(out / "trajectory.csv")
    check(s["steps"] == 0 and s["complete"] and len(rows) == 1, "a zero-length run has the initial row only")


@case
def backward_run_returns(ctx):
    """A negative dt runs backwards; the methods are time-reversible, so running the paper scene
    forward to t = 5 and back from its final state returns to the initial state up to the
    round-off of 100 steps."""
    out = ctx.work / "forward"
    expect_ok(ctx.run("run", "--t-end", "5", "--out", out, "-q"), "forward")
    final = summary(out)["final_state"]["bodies"]
    text = ["[space]", 'kind = "sphere"', "dim = 2"]
    for b in final:
        text += ["[[bodies]]", "mass = 1.0", f"q = {b['q']}", f"p = {b['p']}"]
    text += ["[[potential]]", 'kind = "chord-well"', "theta0 = 0.7853981633974483",
             "[integrator]", "dt = -0.1", "t_end = 5"]
    path = ctx.write("back.toml", "\n".join(text) + "\n")
    back = ctx.work / "back"
    expect_ok(ctx.run("run", path, "--out", back, "-q"), "backward")
    s = summary(back)
    check(s["final_state"]["t"] == -5.0, f"final t {s['final_state']['t']}")
    _, rows = read_csv(out / "trajectory.csv")
    start = rows[0]
    for b, body in enumerate(s["final_state"]["bodies"]):
        q0 = start[1 + 7 * b: 3 + 7 * b]
        p0 = start[3 + 7 * b: 5 + 7 * b]
        worst = max(abs(a - c) for a, c in zip(body["q"] + body["p"], q0 + p0))
        check(worst < 1e-12, f"body {b + 1} returns to within {worst:.3g}")


# ---- runs that fail or are interrupted ---------------------------------------------------------

BLOWUP = """name = "blowup"
# Two bodies flying apart past the chord-well's range (chord sqrt(3)), where its square root is NaN.
[space]
kind = "sphere"
dim = 2
[[bodies]]
mass = 1.0
q = [1.5707963267948966, 0.0]
p = [0.0, -2.0]
[[bodies]]
mass = 1.0
q = [1.5707963267948966, 1.9]
p = [0.0, 2.0]
[[potential]]
kind = "chord-well"
theta0 = 0.7853981633974483
[integrator]
dt = 0.01
t_end = 10.0
output_every = 3
"""


@case
def non_finite_run(ctx):
    path = ctx.write("blowup.toml", BLOWUP)
    out = ctx.work / "out"
    earlier_outputs(out)
    result = ctx.run("run", path, "--out", out)
    err = result.stderr
    check(result.returncode == 3, f"exit status {result.returncode}, expected 3: {err!r}")
    check(err.count("\n") == 1 and err.startswith("sesi: error: "), f"expected one line: {err!r}")
    s = summary(out)
    failure = s["failure"]
    check(s["complete"] is False and s["stop_reason"] == "non-finite state", f"summary {s}")
    check(f"step {failure['step']} " in err and f"t = {failure['t']:g}" in err and f"body {failure['body']}" in err,
          f"stderr does not name step, time and body: {err!r}")
    check(s["steps"] == failure["step"] - 1 and s["final_state"]["t"] < failure["t"], "final state is the last finite one")
    _, rows = read_csv(out / "trajectory.csv")
    check(rows[-1][0] == s["final_state"]["t"] and all(math.isfinite(v) for r in rows for v in r),
          "trajectory.csv must end with the last finite state")
    check(not (out / "plot.png").exists(), "the earlier outputs were not replaced")
    expect_no_staging_left(out)


# ---- the energy guard and the close-encounter floor (issue #5, docs/stability.md) ----------------

def harmonic_scene(dt, steps, guard=None, method="sesi2"):
    """A harmonic pair on E^2 whose relative coordinate has w = 1: Strang's stability limit is
    w dt = 2."""
    lines = ['name = "stiff"', "[space]", 'kind = "euclidean"', "dim = 2",
             "[[bodies]]", "mass = 1.0", "q = [1.0, 1.0]", "p = [0.0, 0.3]",
             "[[bodies]]", "mass = 1.0", "q = [0.0, 0.0]", "p = [0.0, -0.3]",
             "[[potential]]", 'kind = "harmonic-pair"', "k = 0.5",
             "[integrator]", f'method = "{method}"', f"dt = {dt!r}", f"t_end = {dt * steps!r}"]
    if guard is not None:
        lines.append(f"energy_guard = {guard}")
    return "\n".join(lines) + "\n"


def expect_run_failure(ctx, result, out, reason, *words):
    """Exit 3, one stderr line naming the step and time (and words), the summary marked
    incomplete with the reason, and only finite rows kept."""
    err = result.stderr
    check(result.returncode == 3, f"exit status {result.returncode}, expected 3: {err!r}")
    check(err.count("\n") == 1 and err.startswith("sesi: error: "), f"expected one line: {err!r}")
    s = summary(out)
    failure = s["failure"]
    check(s["complete"] is False and s["stop_reason"] == reason, f"stop_reason {s['stop_reason']!r}")
    check(f"step {failure['step']} " in err and f"t = {failure['t']:g}" in err, f"step and time: {err!r}")
    for word in words:
        check(word in err, f"stderr does not say {word!r}: {err!r}")
    _, rows = read_csv(out / "trajectory.csv")
    check(all(math.isfinite(v) for r in rows for v in r), "non-finite numbers in trajectory.csv")
    check(rows[-1][0] == s["final_state"]["t"], "trajectory.csv must end with the last good state")
    expect_no_staging_left(out)
    return s


@case
def energy_guard_trips_above_stability_limit(ctx):
    path = ctx.write("stiff.toml", harmonic_scene(2.04, 200))
    out = ctx.work / "out"
    s = expect_run_failure(ctx, ctx.run("run", path, "--out", out), out, "energy error exceeded",
                           "energy error", "|E - E0| = ", "energy_guard = 100")
    check(s["failure"]["step"] < 30, f"the guard tripped late: step {s['failure']['step']}")


@case
def energy_guard_quiet_below_stability_limit(ctx):
    path = ctx.write("stiff.toml", harmonic_scene(1.96, 2000))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--out", out, "-q"), "stable run at 0.98 of the limit")
    check(summary(out)["complete"] is True, "not complete")


@case
def energy_guard_off(ctx):
    # The same unstable run without the guard: nothing stops it (the energy grows by 1e20).
    path = ctx.write("stiff.toml", harmonic_scene(2.04, 60, guard="false"))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--out", out, "-q"), "energy_guard = false")
    check(summary(out)["energy"]["max_rel_error"] > 1e10, "the run should have blown up")


@case
def energy_guard_from_scene(ctx):
    # A tight guard set in the scene stops the (stable) seed scene at its first steps.
    text = (ctx.source / "examples" / "scenes" / "paper.toml").read_text()
    text = text.replace("[integrator]", "[integrator]\nenergy_guard = 1e-12", 1)
    path = ctx.write("tight.toml", text)
    out = ctx.work / "out"
    expect_run_failure(ctx, ctx.run("run", path, "--out", out, "--t-end", "10"), out, "energy error exceeded",
                       "energy_guard = 1e-12")


HEAD_ON = """name = "head-on"
# Two bodies falling onto each other from rest under cotangent gravity.
[space]
kind = "sphere"
dim = 2
[[bodies]]
mass = 1.0
q = [1.5707963267948966, -0.25]
[[bodies]]
mass = 1.0
q = [1.5707963267948966, 0.25]
[[potential]]
kind = "cotangent-gravity"
G = 1.0
{floor}
[integrator]
dt = 0.001
t_end = 1.0
output_every = 10
"""


@case
def close_encounter_head_on(ctx):
    path = ctx.write("head-on.toml", HEAD_ON.format(floor="min_distance = 0.05"))
    out = ctx.work / "out"
    s = expect_run_failure(ctx, ctx.run("run", path, "--out", out), out, "close encounter",
                           "bodies 1 and 2", "close-encounter floor 0.05", "cotangent-gravity")
    check(0.2 < s["failure"]["t"] < 0.3, f"collision time {s['failure']['t']}")


@case
def close_encounter_head_on_defaults(ctx):
    # With the default floor the steps jump over the encounter; the energy guard stops the run.
    path = ctx.write("head-on.toml", HEAD_ON.format(floor=""))
    out = ctx.work / "out"
    result = ctx.run("run", path, "--out", out)
    check(result.returncode == 3, f"exit status {result.returncode}: {result.stderr!r}")
    s = summary(out)
    check(s["stop_reason"] in ("close encounter", "energy error exceeded"), f"stop_reason {s['stop_reason']!r}")
    _, rows = read_csv(out / "trajectory.csv")
    check(all(math.isfinite(v) for r in rows for v in r), "non-finite numbers in trajectory.csv")


@case
def non_ascii_strings_read_back(ctx):
    # The reader shields toml++ 3.3 from code points it mishandles (U+00A1..U+0499 and others,
    # src/scene_reader.cpp); inside strings and comments they must read back unchanged.
    name = "caf\u00e9-\u0416-\u30a2\u30fc-\ufb30"
    text = (ctx.source / "examples" / "scenes" / "paper.toml").read_text()
    text = f'# Scene \u2014 with \u00e9 and \u3001 in a comment\nname = "{name}"\n' + \
        "\n".join(line for line in text.splitlines() if not line.startswith("name"))
    path = ctx.work / "accents.toml"
    path.write_text(text + "\n", encoding="utf-8")
    result = ctx.run("run", path, "--t-end", "1", cwd=ctx.work)
    expect_ok(result, "scene with non-ASCII strings")
    check(result.stdout.startswith(name + ":"), f"name not read back: {result.stdout[:80]!r}")
    check((ctx.work / "sesi-out" / name / "summary.json").is_file(), "output directory not named after the scene")


def start_long_run(ctx, out, stderr=subprocess.PIPE, quiet=False):
    args = [ctx.sesi, "run", "--t-end", "1e7", "--output-every", "1000000", "--out", str(out)]
    if quiet:
        args.append("--quiet")
    return subprocess.Popen(args, cwd=ctx.work, stdout=subprocess.PIPE, stderr=stderr, stdin=subprocess.DEVNULL)


@case
def interrupted_run(ctx):
    out = ctx.work / "out"
    process = start_long_run(ctx, out)
    time.sleep(0.5)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=60)
    check(process.returncode == 130, f"exit status {process.returncode}, expected 130")
    check(stderr.decode().count("\n") == 1 and b"interrupted" in stderr, f"stderr {stderr!r}")
    s = summary(out)
    check(s["complete"] is False and s["stop_reason"] == "interrupted", f"summary {s['stop_reason']}")
    expect_no_staging_left(out)


def run_on_terminal(ctx, quiet):
    """Run a long scene with stderr on a pseudo-terminal for 1.8 s, then interrupt it; return
    what reached the terminal."""
    master, slave = pty.openpty()
    process = start_long_run(ctx, ctx.work / "out", stderr=slave, quiet=quiet)
    os.close(slave)
    seen = b""
    deadline = time.monotonic() + 1.8
    while time.monotonic() < deadline:
        ready, _, _ = select.select([master], [], [], 0.05)
        if ready:
            try:
                seen += os.read(master, 4096)
            except OSError:
                break
    process.send_signal(signal.SIGINT)
    process.wait(timeout=60)
    while True:
        ready, _, _ = select.select([master], [], [], 0.2)
        if not ready:
            break
        try:
            chunk = os.read(master, 4096)
        except OSError:
            break
        if not chunk:
            break
        seen += chunk
    os.close(master)
    return seen.decode(errors="replace")


@case
def progress_bar_on_terminal(ctx):
    seen = run_on_terminal(ctx, quiet=False)
    check("%" in seen and "[" in seen and "left" in seen, f"no progress bar on the terminal: {seen[:300]!r}")
    check("\r\x1b[K" in seen, "the progress bar was not erased")


@case
def no_progress_bar_when_quiet(ctx):
    seen = run_on_terminal(ctx, quiet=True)
    check("%" not in seen and "left" not in seen, f"--quiet drew a progress bar: {seen[:300]!r}")


@case
def no_progress_bar_without_terminal(ctx):
    out = ctx.work / "out"
    process = start_long_run(ctx, out)
    time.sleep(1.5)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    check(b"%" not in stderr and b"\r" not in stderr, f"progress bar on a pipe: {stderr!r}")


# ---- the example scenes -----------------------------------------------------------------------

def run_example(ctx, stem):
    path = ctx.scene(f"{stem}.toml")
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--t-end", "0.5", "--out", out, "-q"), stem)
    s = summary(out)
    check(s["complete"] and s["steps"] > 0, f"{stem}: {s['stop_reason']}")
    check(abs(s["energy"]["max_rel_error"]) < 1e-3, f"{stem}: relative energy error {s['energy']['max_rel_error']}")


@case
def example_scenes_cover_spaces(ctx):
    stems = {p.stem for p in (ctx.source / "examples" / "scenes").glob("*.toml")}
    check("paper" in stems, "examples/scenes/paper.toml missing")
    for kind in ["sphere", "hyperbolic", "euclidean"]:
        for form in ["qp", "xv"]:
            found = [s for s in stems if s.startswith(kind) and s.endswith(f"-{form}")]
            check(found, f"no {kind} example with {form} initial conditions")


# ---- more cases, one file per theme -------------------------------------------------------------
# tests/program/cases_*.py hold further @case functions. Each runs in this module's namespace, so
# it uses the helpers above (Context, check, expect_input_error, ...) without importing them.
for _extra in sorted(HERE.glob("cases_*.py")):
    exec(compile(_extra.read_text(), str(_extra), "exec"), globals())


# ---- driver ------------------------------------------------------------------------------------

def all_cases(source):
    names = sorted(CASES)
    names += [f"bad_{p.stem}" for p in sorted((HERE / "bad").glob("*.toml"))]
    names += [f"example_{p.stem}" for p in sorted((pathlib.Path(source) / "examples" / "scenes").glob("*.toml"))]
    return names


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--list", action="store_true")
    parser.add_argument("--sesi")
    parser.add_argument("--source", default=str(HERE.parent.parent))
    parser.add_argument("--work")
    parser.add_argument("--case")
    args = parser.parse_args()
    if args.list:
        print("\n".join(all_cases(args.source)))
        return 0
    work = pathlib.Path(args.work) / args.case
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    ctx = Context(args.sesi, args.source, work)
    try:
        if args.case.startswith("bad_"):
            run_bad_scene(ctx, args.case[len("bad_"):])
        elif args.case.startswith("example_") and args.case not in CASES:
            run_example(ctx, args.case[len("example_"):])
        else:
            CASES[args.case](ctx)
    except Skip as e:
        print(f"skipped: {e}")
        return SKIP
    except Failure as e:
        print(f"FAILED {args.case}: {e}")
        return 1
    print(f"passed {args.case}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
