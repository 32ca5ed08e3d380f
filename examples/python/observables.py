"""The observables of a finished run (docs/observables.md): g(r), the mean-squared displacement and
the velocity autocorrelation as NumPy arrays, the numbers `sesi analyze` writes.

    python3 examples/python/observables.py [SESI]

Runs examples/scenes/sphere-two-body-xv.toml with the program (SESI, default `sesi` from PATH)
into runs/demo in the current directory, then reads it.
"""
import pathlib
import subprocess
import sys

program = sys.argv[1] if len(sys.argv) > 1 else "sesi"
scene = pathlib.Path(__file__).resolve().parents[1] / "scenes" / "sphere-two-body-xv.toml"
subprocess.run([program, "run", str(scene), "--out", "runs/demo", "--t-end", "5", "--quiet"], check=True)

import sesi

run = "runs/demo"  # a finished run: sesi run SCENE --out runs/demo
g = sesi.analysis.rdf(run, r_max=3.0, bins=60)       # RDF(r, g, edges, counts, expected, frames, centres)
m = sesi.analysis.msd(run, max_lag=20)               # Correlation(t, value, samples, per_body)
c = sesi.analysis.vacf(run)
f = sesi.analysis.read(run, t_from=1.0)              # Frames(space, dim, radius, t, x, v, masses)
last = sesi.analysis.rdf(f.x[-1], space="sphere", radius=f.radius, r_max=3.0)  # points (bodies, 3)
print(g.counts.sum(), m.value[-1], c.value[0], sesi.analysis.msd_saturation("sphere", 2, f.radius))
