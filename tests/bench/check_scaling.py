#!/usr/bin/env python3
"""Runs a small `sesi bench --scaling` (issue #11) and checks scaling.csv: the columns the docs
name, one row per (N, method, threads) for the space asked for and for the flat E^3 reference,
and a flat cell-list row per N for Lennard-Jones; with sesi2, a row per thermostat (sesi2+langevin,
sesi2+nose-hoover; issue #25) per (N, threads) and its ratio to the NVE sesi2 step in the summary; positive times; pairs per step equal to the
pairs within the cutoff times the force evaluations per step (so ns_per_pair is what it says);
and that bad options are refused with exit status 2, one line naming the option, nothing written.
Topologies (issue #26): --box gives the E^2 box row and a LAMMPS row on the same bodies (when lmp is
on PATH), --genus a row per genus and the E^2 box at the same N, with their ratios in the summary.
LAMMPS on S^2 and S^3 (issue #27): with lmp on PATH a Lennard-Jones sphere run has a `lammps` row (the
E^n box at the same N and density) per (N, threads) and prints "/ LAMMPS E^n (T ranks) RATIO", a finite
positive ratio, for every sphere row; without lmp, or with --no-lammps, no such row and one line saying so.
Timings are not checked: speed targets live in the benchmark (docs/benchmarks.md)."""
import argparse
import csv
import math
import os
import re
import shutil
import subprocess
import sys

COLUMNS = ["n_bodies", "space", "dim", "potential", "method", "threads", "seconds_per_step",
           "pairs_per_step", "ns_per_pair", "peak_rss_mb", "center_distance", "topology"]


def read(path):
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    reader = csv.DictReader(lines)
    return reader.fieldnames, list(reader)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sesi", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    failures = []

    def run(args, out):
        shutil.rmtree(out, ignore_errors=True)
        return subprocess.run([a.sesi, "bench", "--scaling", *args, "--out", out], capture_output=True, text=True)

    for option, args in [("--space", ["--space", "torus"]), ("--n", ["--n", "100,x"]),
                         ("--methods", ["--methods", "sesi3"]), ("--potential", ["--potential", "coulomb"]),
                         ("--center-distance", ["--center-distance", "2"]), ("--threads", ["--threads", "-1"]),
                         ("--center-distance", ["--space", "hyperbolic", "--center-distance", "0,x"]),
                         ("--center-distance", ["--space", "hyperbolic", "--center-distance", "31"]),
                         ("--repeats", ["--repeats", "-1"]), ("--box", ["--box"]),
                         ("--genus", ["--space", "hyperbolic", "--genus", "1"]),
                         ("--genus", ["--space", "hyperbolic", "--genus", "2", "--potential", "cotangent-gravity"])]:
        out = os.path.join(a.work, "scaling-bad")
        r = run(args, out)
        if r.returncode != 2 or len(r.stderr.strip().splitlines()) != 1 or option not in r.stderr or \
                os.path.exists(out):
            failures.append(f"{args}: exit {r.returncode}, stderr {r.stderr!r}, written: {os.path.exists(out)}")

    lmp = shutil.which("lmp") is not None
    cases = [
        (["--space", "sphere", "--dim", "2", "--n", "300,600", "--steps", "5", "--threads", "1,2", "--no-lammps"],
         "sphere", 2, 2, True),
        # issue #27: LAMMPS on the E^2 box beside S^2, one process and mpirun -np 2.
        (["--space", "sphere", "--dim", "2", "--n", "1000", "--steps", "40", "--threads", "1,2"], "sphere", 2, 2, True),
        (["--space", "hyperbolic", "--dim", "2", "--center-distance", "0,5", "--n", "300", "--steps", "5",
          "--repeats", "2"],
         "hyperbolic", 2, 1, True),
        (["--space", "sphere", "--dim", "3", "--n", "300", "--steps", "5", "--methods", "sesi2,sesi4"],
         "sphere", 3, 1, True),
        (["--space", "sphere", "--dim", "2", "--potential", "cotangent-gravity", "--n", "100", "--steps", "4",
          "--methods", "sesi4"], "sphere", 2, 1, False),
    ]
    stages = {"sesi2": 1, "sesi4": 3, "sesi2+langevin": 1, "sesi2+nose-hoover": 1}
    thermostats = ["sesi2+langevin", "sesi2+nose-hoover"]
    for args, space, dim, threads_given, lj in cases:
        out = os.path.join(a.work, f"scaling-{space}{dim}{'-lj' if lj else '-gravity'}")
        r = run(args, out)
        sys.stderr.write(r.stderr)
        if r.returncode != 0:
            failures.append(f"{args}: exit {r.returncode}: {r.stderr.strip()}")
            continue
        path = os.path.join(out, "scaling.csv")
        if os.path.exists(path + ".partial"):
            failures.append(f"{args}: scaling.csv.partial left behind")
        fields, rows = read(path)
        if fields != COLUMNS:
            failures.append(f"{args}: columns {fields}")
            continue
        sizes = [int(n) for n in args[args.index("--n") + 1].split(",")]
        methods = args[args.index("--methods") + 1].split(",") if "--methods" in args else ["sesi2"]
        distances = [float(d) for d in args[args.index("--center-distance") + 1].split(",")] \
            if "--center-distance" in args else [0.0]
        timed = len(thermostats) * threads_given if "sesi2" in methods else 0
        # LAMMPS rows: S^2 and S^3 Lennard-Jones, one per (N, threads), unless left out.
        lammps_asked = lj and space == "sphere" and dim in (2, 3) and "--no-lammps" not in args
        lammps = lammps_asked and lmp
        expected = len(sizes) * (len(methods) * threads_given * (len(distances) + 1) + timed + (1 if lj else 0) +
                                 (threads_given if lammps else 0))
        if len(rows) != expected:
            failures.append(f"{args}: {len(rows)} rows, expected {expected}")
        for row in rows:
            t = float(row["seconds_per_step"])
            pairs = float(row["pairs_per_step"])
            n = int(row["n_bodies"])
            if row["space"] == "lammps":  # its peak memory is not measured
                if not lammps or (row["dim"], row["method"], row["topology"]) != (str(dim), "velocity-verlet", "box") \
                        or not t > 0 or not 0.5 * n < pairs < 20 * n:
                    failures.append(f"{args}: unexpected LAMMPS row {row}")
                continue
            if not t > 0 or not float(row["peak_rss_mb"]) > 0 or not pairs > 0:
                failures.append(f"{args}: non-positive figure in {row}")
                continue
            if abs(float(row["ns_per_pair"]) - t / pairs * 1e9) > 1e-3 * t / pairs * 1e9:
                failures.append(f"{args}: ns_per_pair {row['ns_per_pair']} is not seconds / pairs")
            d = float(row["center_distance"])
            if (row["space"] == "hyperbolic" and d not in distances) or (row["space"] != "hyperbolic" and d != 0):
                failures.append(f"{args}: center_distance {d} in {row}")
            if row["space"] == "flat-periodic":
                continue
            if row["space"] not in (space, "euclidean") or (row["space"] == "euclidean" and row["dim"] != "3"):
                failures.append(f"{args}: unexpected row {row}")
            per_step = stages[row["method"]]
            if not lj and pairs != n * (n - 1) / 2 * per_step:
                failures.append(f"{args}: gravity pairs per step {pairs}, expected {n * (n - 1) / 2 * per_step}")
            if lj and not (0.5 * n * per_step < pairs < 20 * n * per_step):
                failures.append(f"{args}: {pairs} Lennard-Jones pairs per step at density 1/2 for {n} bodies")
        if "sesi2" in methods:
            for n in sizes:
                for name in thermostats:
                    got = [row for row in rows if row["method"] == name and int(row["n_bodies"]) == n]
                    if len(got) != threads_given or any(row["space"] != space for row in got):
                        failures.append(f"{args}: {len(got)} {name} rows at N = {n}, expected {threads_given}")
            if "/ NVE sesi2" not in r.stdout:
                failures.append(f"{args}: no thermostat / NVE ratio in the summary")
        if len(distances) > 1:
            for n in sizes:
                seen = sorted(float(row["center_distance"]) for row in rows
                              if row["space"] == space and int(row["n_bodies"]) == n and "+" not in row["method"])
                if seen != sorted(distances):
                    failures.append(f"{args}: distances {seen} at N = {n}")
            if "far (5 R) / origin" not in r.stdout:
                failures.append(f"{args}: no far / origin ratio in the summary")
        if "--threads" in args:
            counts = sorted({row["threads"] for row in rows if row["space"] == space})
            if counts != ["1", "2"]:
                failures.append(f"{args}: thread counts {counts}")
        if lammps:
            # One LAMMPS row per (N, threads) of the sesi rows, its ranks the threads, and every
            # sphere row's ratio to it in the summary, finite and positive.
            for n in sizes:
                want = sorted(row["threads"] for row in rows if row["space"] == space and row["method"] == methods[0]
                              and int(row["n_bodies"]) == n)
                got = sorted(row["threads"] for row in rows if row["space"] == "lammps" and int(row["n_bodies"]) == n)
                if got != want:
                    failures.append(f"{args}: LAMMPS rows at N = {n} for threads {got}, expected {want}")
            ratios = 0
            for line in r.stdout.splitlines():
                head = re.match(rf"\s*\d+ bodies {space}\s+{dim} \S+\s+(\d+) thr:", line)
                if not head:
                    continue
                found = re.search(r"/ LAMMPS E\^(\d) \((\d+) ranks\) (\S+)", line)
                value = float(found.group(3)) if found else math.nan
                if not found or found.group(1) != str(dim) or found.group(2) != head.group(1) or \
                        not (math.isfinite(value) and value > 0):
                    failures.append(f"{args}: no finite positive LAMMPS E^{dim} ratio for the same threads in {line!r}")
                ratios += 1
            if ratios != sum(row["space"] == space for row in rows):
                failures.append(f"{args}: {ratios} sphere rows with a LAMMPS ratio in the summary, expected "
                                f"{sum(row['space'] == space for row in rows)}")
        elif lammps_asked or "--no-lammps" in args:
            if "LAMMPS rows left out: " not in r.stdout or "/ LAMMPS" in r.stdout:
                failures.append(f"{args}: without LAMMPS, no line saying the rows are left out, or a ratio to LAMMPS")
    # Topologies (issue #26): the rows in order, their figures, and the ratios of the summary.
    for args, expected, ratios in [
            (["--space", "euclidean", "--dim", "2", "--box", "--n", "300", "--steps", "5", "--threads", "1"],
             [("euclidean", "2", "sesi2", "box")] + ([("lammps", "2", "velocity-verlet", "box")] if lmp else []),
             ["/ LAMMPS (1 ranks)"] if lmp else []),
            (["--space", "hyperbolic", "--dim", "2", "--genus", "2,3", "--n", "300", "--steps", "5"],
             [("hyperbolic", "2", "sesi2", "genus 2"), ("hyperbolic", "2", "sesi2", "genus 3"),
              ("euclidean", "2", "sesi2", "box")], ["/ E^2 box", "/ genus 2"])]:
        out = os.path.join(a.work, "scaling-topology")
        r = run(args, out)
        sys.stderr.write(r.stderr)
        if r.returncode != 0:
            failures.append(f"{args}: exit {r.returncode}: {r.stderr.strip()}")
            continue
        fields, rows = read(os.path.join(out, "scaling.csv"))
        got = [(row["space"], row["dim"], row["method"], row["topology"]) for row in rows]
        if fields != COLUMNS or got != expected:
            failures.append(f"{args}: columns {fields}, rows {got}, expected {expected}")
            continue
        for row in rows:
            t, pairs, n = float(row["seconds_per_step"]), float(row["pairs_per_step"]), int(row["n_bodies"])
            if not t > 0 or not (0.5 * n < pairs < 20 * n):
                failures.append(f"{args}: {t} s per step, {pairs} Lennard-Jones pairs for {n} bodies in {row}")
        for text in ratios:
            if text not in r.stdout:
                failures.append(f"{args}: no '{text}' ratio in the summary")

    for f in failures:
        print("FAIL:", f)
    print("ok" if not failures else f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
