#!/usr/bin/python3
"""method = "auto" against the bench's best fixed choice (issue #15; docs/benchmarks.md).

    /usr/bin/python3 tools/auto_vs_bench.py SESI [--t-end T] [--tols 1e-6,1e-9] [SCENE]

For each tolerance TOL: `SESI bench --horizons T --levels TOL*|E0|` over the methods of `sesi run`
of order 4 and up (the least wall time of a fixed method and step reaching max |E - E0| <= the
level; E0 the scene's initial energy, so the level is TOL's relative error), then `SESI run
--tolerance TOL`, and `SESI run` of the bench's best (method, dt) with the same checks and
outputs. Prints the auto run's max relative energy error over TOL, its force evaluations (steps x
stages, the reads of processed methods aside) over the best's in the bench, and its wall time
(alone, and with its pilot runs) over the best fixed choice's `sesi run` time and its bench time.
SCENE: a scene file (default: the seed's scene, as `sesi run` without one; its bench scene
`paper`).
"""
import argparse
import csv
import json
import pathlib
import subprocess
import sys
import tempfile


def run(*args):
    result = subprocess.run([str(a) for a in args], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"{' '.join(map(str, args))}: exit {result.returncode}: {result.stderr.strip()}")
    return result


def best_of(sesi, out, args, repeats=5):
    """The summary of the run with the least wall time of `repeats` runs."""
    best = None
    for _ in range(repeats):
        run(sesi, "run", *args, "--out", out, "-q")
        s = json.loads((out / "summary.json").read_text())
        if best is None or s["wall_seconds"] < best["wall_seconds"]:
            best = s
        for f in out.iterdir():
            f.unlink()
        out.rmdir()
    return best


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sesi")
    ap.add_argument("scene", nargs="?")
    ap.add_argument("--t-end", default="800")
    ap.add_argument("--tols", default="1e-6,1e-9")
    o = ap.parse_args()
    sesi = pathlib.Path(o.sesi).resolve()
    scene = [o.scene] if o.scene else []
    listed = json.loads(run(sesi, "run", "--list-methods", "--json").stdout)["methods"]
    stages = {m["name"]: m["stages"] for m in listed}
    methods = [m["name"] for m in listed if m["order"] >= 4]
    work = pathlib.Path(tempfile.mkdtemp(prefix="auto-vs-bench-"))
    probe = work / "probe"
    run(sesi, "run", *scene, "--t-end", "0", "--method", "sesi4", "--dt", "1", "--out", probe, "-q")
    e0 = abs(json.loads((probe / "summary.json").read_text())["energy"]["initial"])
    print(f"| scene, T | TOL | auto: method, dt | error / TOL | bench's best: method, dt | force evaluations / best's | "
          f"auto run / best run | with pilots | auto run / best in the bench |")
    print("|---|---|---|---|---|---|---|---|---|")
    for tol in o.tols.split(","):
        level = float(tol) * e0
        bench = work / f"bench-{tol}"
        run(sesi, "bench", "--scene", scene[0] if scene else "paper", "--horizons", o.t_end, "--levels", f"{level:.6g}",
            "--methods", ",".join(methods), "--out", bench)
        rows = [r for r in csv.DictReader(l for l in open(bench / "horizons.csv") if not l.startswith("#"))
                if r["reached"] == "yes"]
        best = min(rows, key=lambda r: float(r["wall_seconds"]))
        auto = best_of(sesi, work / "auto", [*scene, "--tolerance", tol, "--t-end", o.t_end])
        fixed = best_of(sesi, work / "fixed", [*scene, "--method", best["method"], "--dt", best["dt_or_tol"],
                                               "--t-end", o.t_end, "--output-every", str(auto["output_every"])])
        a = auto["auto"]
        name = scene[0] if scene else "seed (paper)"
        print(f"| {name}, {o.t_end} | {tol} | {auto['method']}, {auto['dt']:.4g} | {a['error_over_tolerance']:.2f} | "
              f"{best['method']}, {float(best['dt_or_tol']):.4g} | "
              f"{auto['steps'] * stages[auto['method']] / float(best['force_evals']):.2f} | "
              f"{auto['wall_seconds'] / fixed['wall_seconds']:.2f} | "
              f"{(auto['wall_seconds'] + a['pilot_seconds']) / fixed['wall_seconds']:.2f} | "
              f"{auto['wall_seconds'] / float(best['wall_seconds']):.2f} |")


if __name__ == "__main__":
    main()
