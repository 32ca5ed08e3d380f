#!/usr/bin/env python3
"""Runs a small `sesi bench --scaling --ranks` (issue #27; docs/parallel.md) and checks ranks.csv:
the columns, two rows per (N, T), one process of T threads and T ranks of one thread, the same
steps timed in both, positive times and memory, outputs identical (the bench compares them) and
the ratio line per (N, T) in the summary; and that bad options are refused with exit status 2, one
line naming the option, nothing written: --ranks without --scaling, off S^2 Lennard-Jones, with
one thread, and without mpirun on PATH. Timings are not checked: the target (within 1.15x at 10^5
bodies) lives in the benchmark (docs/parallel.md)."""
import argparse
import csv
import os
import re
import shutil
import subprocess
import sys

COLUMNS = ["n_bodies", "method", "ranks", "threads_per_rank", "steps", "seconds_per_step", "peak_rss_mb", "identical"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sesi", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    failures = []
    os.makedirs(a.work, exist_ok=True)

    def run(args, out, env=None):
        shutil.rmtree(out, ignore_errors=True)
        return subprocess.run([a.sesi, "bench", *args, "--out", out], capture_output=True, text=True, env=env,
                              stdin=subprocess.DEVNULL, timeout=500)

    no_mpirun = dict(os.environ, PATH="/nonexistent")
    for option, args, env in [("--ranks", ["--ranks"], None),
                              ("--ranks", ["--scaling", "--ranks", "--space", "hyperbolic"], None),
                              ("--ranks", ["--scaling", "--ranks", "--potential", "cotangent-gravity"], None),
                              ("--threads", ["--scaling", "--ranks", "--threads", "1"], None),
                              ("--n", ["--scaling", "--ranks", "--n", "100"], None),
                              ("--methods", ["--scaling", "--ranks", "--methods", "geodesic2"], None),
                              ("mpirun", ["--scaling", "--ranks", "--n", "1000"], no_mpirun)]:
        out = os.path.join(a.work, "ranks-bad")
        r = run(args, out, env)
        if r.returncode != 2 or len(r.stderr.strip().splitlines()) != 1 or option not in r.stderr or \
                os.path.exists(out):
            failures.append(f"{args}: exit {r.returncode}, stderr {r.stderr!r}, written: {os.path.exists(out)}")

    out = os.path.join(a.work, "ranks")
    sizes, counts = [600], [2, 3]
    r = run(["--scaling", "--ranks", "--n", ",".join(map(str, sizes)), "--threads", ",".join(map(str, counts)),
             "--steps", "20"], out)
    sys.stderr.write(r.stderr)
    if r.returncode != 0:
        failures.append(f"exit {r.returncode}: {r.stderr.strip()}")
    else:
        if os.path.exists(os.path.join(out, "ranks.csv.partial")):
            failures.append("ranks.csv.partial left behind")
        with open(os.path.join(out, "ranks.csv")) as f:
            reader = csv.DictReader(line for line in f if not line.startswith("#"))
            rows = list(reader)
        if reader.fieldnames != COLUMNS:
            failures.append(f"columns {reader.fieldnames}")
        want = [(n, ranks, threads) for n in sizes for t in counts for ranks, threads in ((1, t), (t, 1))]
        got = [(int(row["n_bodies"]), int(row["ranks"]), int(row["threads_per_rank"])) for row in rows]
        if got != want:
            failures.append(f"rows (n, ranks, threads) {got}, expected {want}")
        for row in rows:
            # --steps 20: both runs step 20 times (the profile's step count), one method, sesi2.
            if row["steps"] != "20" or row["method"] != "sesi2" or row["identical"] != "yes" or \
                    not float(row["seconds_per_step"]) > 0 or not float(row["peak_rss_mb"]) > 0:
                failures.append(f"row {row}")
        for n in sizes:
            for t in counts:
                pattern = rf"{n} bodies sesi2\s+{t} ranks x 1 thread / 1 rank x {t} threads: time per step (\S+), " \
                          rf"peak memory per process (\S+); outputs identical"
                found = re.search(pattern, r.stdout)
                if not found or not all(float(v.rstrip(",;")) > 0 for v in found.groups()):
                    failures.append(f"no ratio line for {n} bodies, {t} ranks in {r.stdout!r}")

    for f in failures:
        print("FAIL:", f)
    print("ok" if not failures else f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
