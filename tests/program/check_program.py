#!/usr/bin/env python3
"""Tests of the `sesi` program, one ctest test per case (tests/program/CMakeLists.txt).

    check_program.py --list
    check_program.py --sesi PATH --source REPO --work DIR --case NAME

This file is the driver and the helpers every theme shares. The cases live beside it, in one
folder per part of the program (src/<part>), in files <part>/cases_*.py:

    cli/           the command line: arguments, --help, the default scene, progress, interrupts
    scene/         reading scenes: bad scenes (scene/bad/*.toml, case bad_<stem>; each file's header
                   says which key, line and message sesi must report), the reader's limits, the
                   example scenes (examples/scenes/*.toml, case example_<stem>), dimensions
    run/           the run loop: time grid, failures, energy guard, checkpoints and resume, far out
    outputs/       the output directory and the files in it (and check_h5md.py, its own test)
    integrators/   the methods (and test_runtime_composition.cpp, a C++ test)

Each cases file is exec'd in this module's namespace, so its @case functions use the helpers here
(Context, check, expect_input_error, ...) without importing them. Standard library only.
Exit status 0 passes, 77 skips (ctest SKIP_RETURN_CODE; a "SKIPPED: reason" line says why, raise
Skip(reason) only for a missing optional part), anything else fails.
"""
import argparse
import json
import math
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import time

HERE = pathlib.Path(__file__).resolve().parent
SKIP = 77
METHODS = {"sesi2": 2, "sesi4": 4, "sesi4-suzuki": 4, "sesi4-mclachlan": 4, "sesi6": 6,
           "sesi6-kahan-li": 6, "sesi8": 8, "sesi8-kahan-li": 8}
OUTPUTS = ["trajectory.csv", "diagnostics.csv", "summary.json"]

CASES = {}


def case(function):
    CASES[function.__name__] = function
    return function


# Generated cases (bad_<stem>, example_<stem>): a prefix, a function giving the stems for a
# source tree and a function running one stem. Case files add theirs with case_family.
CASE_FAMILIES = []


def case_family(prefix, stems, run):
    CASE_FAMILIES.append((prefix, stems, run))


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
    # The earlier run's manifest, with the plot that tools/plot_run.py added to it.
    (directory / "sesi-manifest.txt").write_text("# sesi-manifest 1: earlier\n" + "\n".join(OUTPUTS + ["plot.png"]) + "\n")
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


# ---- a run that fails: non-finite numbers (run/, outputs/ and scene/ cases use it) -------------

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


# ---- a long run of the default scene, to interrupt (cli/ and outputs/ cases use it) ------------

def start_long_run(ctx, out, stderr=subprocess.PIPE, quiet=False):
    args = [ctx.sesi, "run", "--t-end", "1e7", "--output-every", "1000000", "--out", str(out)]
    if quiet:
        args.append("--quiet")
    return subprocess.Popen(args, cwd=ctx.work, stdout=subprocess.PIPE, stderr=stderr, stdin=subprocess.DEVNULL)


# ---- the cases, one folder per part of the program, one file per theme -------------------------
# tests/program/*/cases_*.py hold the @case functions. Each runs in this module's namespace, so
# it uses the helpers above (Context, check, expect_input_error, ...) without importing them.
for _extra in sorted(HERE.glob("*/cases_*.py")):
    exec(compile(_extra.read_text(), str(_extra), "exec"), globals())


# ---- driver ------------------------------------------------------------------------------------

def all_cases(source):
    names = sorted(CASES)
    for prefix, stems, _ in CASE_FAMILIES:
        names += [f"{prefix}{stem}" for stem in stems(source)]
    return names


def run_case(ctx, name):
    for prefix, _, run in CASE_FAMILIES:
        if name.startswith(prefix) and name not in CASES:
            return run(ctx, name[len(prefix):])
    return CASES[name](ctx)


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
        run_case(ctx, args.case)
    except Skip as e:
        # ctest shows no output of a skipped test: tests/check_skips.cmake reads this line from its JUnit file.
        print(f"SKIPPED: {str(e).removeprefix('SKIPPED: ')}")
        return SKIP
    except Failure as e:
        print(f"FAILED {args.case}: {e}")
        return 1
    print(f"passed {args.case}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
