#!/usr/bin/env python3
"""Runs `sesi bench --quick` on one scene and checks work_precision.csv (issue #4):
the header and columns, one or more rows per method (all methods of the scene), finite
non-negative numbers, steps and force evaluations growing as the step (tolerance) falls, and
every method's final error falling from its coarsest to its finest run, the force evaluations of
`sesi run --list-methods`'s stages per step; the form the sesi rows
ran in (`# sesi rows:`, the scene's default or --form); and that a bad --form is refused with
exit status 2, one line, and nothing written. No wall-clock limit: ctest's TIMEOUT is the hang
guard (a sanitizer build runs several times slower)."""
import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys

COLUMNS = ["method", "order", "dt_or_tol", "steps", "force_evals", "wall_seconds", "final_error",
           "max_energy_error", "max_momentum_drift"]
# Round-off of a quick run's final positions (unit scale): a few hundred steps of up to 23
# stages, each rounding at about eps: 400 * 23 * 2.2e-16 = 2e-12.
ROUNDOFF = 2e-12
# The bench's methods: every method of `sesi run` (read from `sesi run --list-methods --json`)
# and these references, which only the bench runs.
REFERENCES = ["dopri5", "rk78", "bulirsch-stoer", "rk4", "implicit-midpoint", "gauss4", "tao2", "tao4",
              "rattle"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sesi", required=True)
    ap.add_argument("--source", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--form", default="")
    a = ap.parse_args()
    out = os.path.join(a.work, a.scene + (f"-{a.form}" if a.form else ""))
    shutil.rmtree(out, ignore_errors=True)
    scene = a.scene
    if scene == "file":
        scene = os.path.join(a.source, "examples", "scenes", "paper.toml")
    failures = []
    listed = subprocess.run([a.sesi, "run", "--list-methods", "--json"], capture_output=True, text=True)
    if listed.returncode != 0:
        print(f"FAIL: sesi run --list-methods --json: exit {listed.returncode}, {listed.stderr!r}")
        return 1
    listed = {m["name"]: m for m in json.loads(listed.stdout)["methods"]}
    methods = list(listed) + REFERENCES
    # A bad --form: exit status 2, one line naming the option, no output directory.
    bad_out = out + "-bad-form"
    shutil.rmtree(bad_out, ignore_errors=True)
    bad = subprocess.run([a.sesi, "bench", "--quick", "--scene", scene, "--form", "kdk",
                          "--out", bad_out], capture_output=True, text=True)
    if bad.returncode != 2 or len(bad.stderr.strip().splitlines()) != 1 or \
            "--form" not in bad.stderr or os.path.exists(bad_out):
        failures.append(f"--form kdk: exit {bad.returncode}, stderr {bad.stderr!r}, "
                        f"output written: {os.path.exists(bad_out)}")
    # The form of the sesi rows: the scene's default, or --form (re-charting on a scene file).
    form = a.form or ("seed" if a.scene.startswith("kepler") else "program")
    expected = {"seed": "drift-kick-drift form (the seed's), no re-charting",
                "program": ("kick-drift-kick form with re-charting" if a.scene == "file"
                            else "kick-drift-kick form, as sesi run steps, no re-charting")}[form]
    command = [a.sesi, "bench", "--quick", "--scene", scene, "--out", out]
    if a.form:
        command += ["--form", a.form]
    run = subprocess.run(command, capture_output=True, text=True)
    sys.stderr.write(run.stderr)
    if run.returncode != 0:
        print(f"FAIL: exit status {run.returncode}")
        return 1
    with open(os.path.join(out, "work_precision.csv")) as f:
        lines = f.read().splitlines()
    notes = [l for l in lines if l.startswith("#")]
    body = [l for l in lines if not l.startswith("#")]
    if not any(n.startswith("# reference: ") for n in notes):
        failures.append("no '# reference:' comment line")
    if not any(n.startswith("# sesi rows: ") and expected in n for n in notes):
        failures.append(f"no '# sesi rows:' line saying {expected!r}")
    if body[0].split(",") != COLUMNS:
        failures.append(f"header {body[0]!r}")
    rows = list(csv.DictReader(body))
    by_method = {}
    for r in rows:
        for k in COLUMNS[1:]:
            v = float(r[k])
            if not math.isfinite(v) or v < 0:
                failures.append(f"{r['method']}: {k} = {r[k]}")
        by_method.setdefault(r["method"], []).append(r)
    for m in methods:
        runs = by_method.get(m, [])
        if m.startswith("tao") and a.scene.startswith("kepler"):
            # Tao's method with its default binding omega = 20 (reference/tao.hpp) diverges at
            # most of these steps on the Kepler scenes (docs/benchmarks.md): not required here.
            continue
        if len(runs) < 2:
            failures.append(f"{m}: {len(runs)} rows (want >= 2)")
            continue
        # Coarsest first: steps grow as dt or the tolerance falls.
        runs.sort(key=lambda r: -float(r["dt_or_tol"]))
        steps = [int(r["steps"]) for r in runs]
        # (Bulirsch-Stoer may take fewer, higher-order steps at a tighter tolerance.)
        if m not in ("dopri5", "rk78", "bulirsch-stoer") and steps != sorted(steps):
            failures.append(f"{m}: steps {steps} do not grow as the step falls")
        errors = [float(r["final_error"]) for r in runs]
        # Below ROUNDOFF both runs are at round-off (sesi10-processed on the seed's scene at the
        # quick sweep's dt = 0.1 and 0.05: 4e-14 and 6e-14): they need not fall.
        if not errors[-1] < errors[0] and errors[0] > ROUNDOFF:
            failures.append(f"{m}: final error {errors} does not fall with the step")
        if float(runs[-1]["force_evals"]) <= 0:
            failures.append(f"{m}: no force evaluations counted")
        # The list's stages are the force evaluations per step: exactly steps x stages, and more
        # for a processed method (its processor where the state is read).
        if m in listed:
            stages, processed = listed[m]["stages"], listed[m]["processed"]
            for r in runs:
                steps, evals = int(r["steps"]), int(r["force_evals"])
                if evals < steps * stages or (not processed and evals != steps * stages):
                    failures.append(f"{m}: {evals} force evaluations in {steps} steps of {stages} stages")
    unknown = set(by_method) - set(methods)
    if unknown:
        failures.append(f"unknown methods {sorted(unknown)}")
    for f in failures:
        print("FAIL:", f)
    print(f"{len(rows)} rows, {len(by_method)} methods")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
