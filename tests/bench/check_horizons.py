#!/usr/bin/env python3
"""Runs a quick `sesi bench --horizons` (issue #15) on the seed's scene and checks horizons.csv:
its columns, one row per method, horizon and level (the default methods: the sesi compositions,
dopri5, rk78), finite times and counts where a level is reached, that the row is the fastest run
of horizon_runs.csv reaching the level, and that a smaller level is never reached faster than a
larger one (its runs are a subset). Also `--dts`/`--tols` in the ordinary sweep (the rows use
exactly those settings; the '# sampling:' line counts the steps that do not divide the sample
spacing), and that bad values are refused with exit status 2, one line naming the option,
nothing written. Timings are not compared with anything (ctest's TIMEOUT is the hang guard): targets
live in the benchmark."""
import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys

COLUMNS = ["method", "order", "horizon", "level", "reached", "dt_or_tol", "steps", "force_evals",
           "wall_seconds", "max_energy_error", "runs", "best_error"]
RUN_COLUMNS = ["method", "order", "horizon", "dt_or_tol", "steps", "force_evals", "wall_seconds",
               "timed_runs", "max_energy_error", "max_momentum_drift", "samples"]
HORIZONS = [20.0, 40.0]
LEVELS = [1e-4, 1e-7]


def read(path):
    with open(path) as f:
        lines = f.read().splitlines()
    notes = [l for l in lines if l.startswith("#")]
    reader = csv.DictReader([l for l in lines if not l.startswith("#")])
    return notes, reader.fieldnames, list(reader)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sesi", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    failures = []

    def bench(args, out):
        shutil.rmtree(out, ignore_errors=True)
        return subprocess.run([a.sesi, "bench", *args, "--out", out], capture_output=True, text=True)

    # Bad values: exit status 2, one line naming the option, no output directory.
    bad_out = os.path.join(a.work, "horizons-bad")
    for option, args in [("--dts", ["--dts", "0"]), ("--dts", ["--dts", "0.1,abc"]),
                         ("--tols", ["--tols", "1e-6,x"]), ("--tols", ["--tols", "-1e-6"]),
                         ("--levels", ["--horizons", "20", "--levels", "-1"]),
                         ("--levels", ["--horizons", "20", "--levels", "1e-6,,1e-7"]),
                         ("--levels", ["--levels", "1e-6"]),
                         ("--horizons", ["--horizons", "abc"]), ("--horizons", ["--horizons", "0,20"]),
                         ("--horizons", ["--horizons", "20", "--t-end", "30"]),
                         ("--dts", ["--horizons", "20,40", "--dts", "30"]),
                         ("--budget", ["--budget", "-1"])]:
        r = bench(["--quick", "--scene", "paper", *args], bad_out)
        lines = r.stderr.strip().splitlines()
        if r.returncode != 2 or len(lines) != 1 or option not in r.stderr or os.path.exists(bad_out):
            failures.append(f"{' '.join(args)}: exit {r.returncode}, stderr {r.stderr!r}, "
                            f"written: {os.path.exists(bad_out)}")

    # The horizon default: every method of `sesi run` (its machine-readable list) and the two
    # odeint methods of the targets.
    listed = subprocess.run([a.sesi, "run", "--list-methods", "--json"], capture_output=True, text=True)
    if listed.returncode != 0:
        print(f"FAIL: sesi run --list-methods --json: exit {listed.returncode}, {listed.stderr!r}")
        return 1
    methods = [m["name"] for m in json.loads(listed.stdout)["methods"]] + ["dopri5", "rk78"]

    out = os.path.join(a.work, "horizons")
    run = bench(["--quick", "--scene", "paper", "--horizons", ",".join(f"{h:g}" for h in HORIZONS),
                 "--levels", ",".join(f"{l:g}" for l in LEVELS)], out)
    sys.stderr.write(run.stderr)
    if run.returncode != 0:
        print(f"FAIL: exit status {run.returncode}")
        return 1
    if "horizon sweep" not in run.stdout:
        failures.append("no summary on stdout")
    notes, header, rows = read(os.path.join(out, "horizons.csv"))
    run_notes, run_header, runs = read(os.path.join(out, "horizon_runs.csv"))
    if header != COLUMNS:
        failures.append(f"horizons.csv header {header}")
    if run_header != RUN_COLUMNS:
        failures.append(f"horizon_runs.csv header {run_header}")
    for needed in ("# errors sampled at the 201 times", "# sampling:", "# wall_seconds:"):
        if not any(n.startswith(needed) for n in notes):
            failures.append(f"no '{needed}' line in horizons.csv")
    table = {}
    for r in rows:
        key = (r["method"], float(r["horizon"]), float(r["level"]))
        if key in table:
            failures.append(f"duplicate row {key}")
        table[key] = r
    expected = {(m, h, l) for m in methods for h in HORIZONS for l in LEVELS}
    if set(table) != expected:
        failures.append(f"rows missing {sorted(expected - set(table))}, extra {sorted(set(table) - expected)}")
    by_run = {}
    for r in runs:
        by_run.setdefault((r["method"], float(r["horizon"])), []).append(r)
    for key, r in sorted(table.items()):
        m, h, level = key
        mine = by_run.get((m, h), [])
        if int(r["runs"]) != len(mine):
            failures.append(f"{key}: runs {r['runs']} but {len(mine)} in horizon_runs.csv")
        reaching = [x for x in mine if float(x["max_energy_error"]) <= level]
        if r["reached"] == "yes":
            nums = [float(r[c]) for c in ("dt_or_tol", "steps", "force_evals", "wall_seconds")]
            if not all(math.isfinite(v) and v > 0 for v in nums):
                failures.append(f"{key}: reached with {nums}")
            if not float(r["max_energy_error"]) <= level:
                failures.append(f"{key}: error {r['max_energy_error']} above the level")
            fastest = min(float(x["wall_seconds"]) for x in reaching) if reaching else math.nan
            if float(r["wall_seconds"]) != fastest:
                failures.append(f"{key}: {r['wall_seconds']} s, not the fastest reaching run ({fastest})")
        elif r["reached"] == "no":
            if reaching:
                failures.append(f"{key}: 'no' but {len(reaching)} runs reach it")
        else:
            failures.append(f"{key}: reached = {r['reached']!r}")
    # By construction: the runs reaching a smaller level are some of those reaching a larger one.
    for m in methods:
        for h in HORIZONS:
            big, small = table.get((m, h, max(LEVELS))), table.get((m, h, min(LEVELS)))
            if not big or not small or small["reached"] != "yes":
                continue
            if big["reached"] != "yes" or float(small["wall_seconds"]) < float(big["wall_seconds"]):
                failures.append(f"{m} at {h}: level {min(LEVELS)} in {small['wall_seconds']} s, "
                                f"level {max(LEVELS)}: {big['reached']} {big['wall_seconds']}")
    # Somebody must reach the loose level on this short run (else the ladders are off).
    if not any(r["reached"] == "yes" for k, r in table.items() if k[2] == max(LEVELS)):
        failures.append(f"no method reaches {max(LEVELS)}")

    # --dts and --tols in the ordinary sweep, the same for every method of the family.
    out = os.path.join(a.work, "dts")
    run = bench(["--quick", "--scene", "paper", "--methods", "sesi4,rk4,dopri5", "--dts", "0.1,0.07",
                 "--tols", "1e-6,1e-8"], out)
    if run.returncode != 0:
        failures.append(f"--dts sweep: exit {run.returncode}: {run.stderr[-300:]}")
    else:
        notes, _, rows = read(os.path.join(out, "work_precision.csv"))
        got = sorted((r["method"], float(r["dt_or_tol"])) for r in rows)
        want = sorted([("sesi4", 0.1), ("sesi4", 0.07), ("rk4", 0.1), ("rk4", 0.07),
                       ("dopri5", 1e-6), ("dopri5", 1e-8)])
        if got != want:
            failures.append(f"--dts sweep rows {got}")
        # t_end 20, 200 samples: spacing 0.1, so dt 0.07 does not divide it (2 of 4 runs).
        if not any(n.startswith("# sampling: 2 of 4 fixed-step runs") for n in notes):
            failures.append(f"--dts sweep: no '# sampling: 2 of 4' line in {notes}")
    for f in failures:
        print("FAIL:", f)
    print(f"{len(table)} rows, {len(runs)} runs")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
