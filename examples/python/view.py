#!/usr/bin/python3
"""The viewer from Python (docs/python.md, docs/view.md): five Lennard-Jones bodies circling on the
hyperbolic plane H^2, run, and their run saved as one HTML page to open in a browser (in Jupyter,
a sesi.View shows inline).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/view.py
"""
import os
import tempfile

import numpy as np

import sesi

# Five bodies on the circle at distance 0.6 from the origin of H^2 (the hyperboloid's point
# (sinh d cos phi, sinh d sin phi, cosh d)), each moving along the circle at speed 0.3.
d, phi = 0.6, 2 * np.pi * np.arange(5) / 5
x = np.column_stack([np.sinh(d) * np.cos(phi), np.sinh(d) * np.sin(phi), np.full(5, np.cosh(d))])
v = 0.3 * np.column_stack([-np.sin(phi), np.cos(phi), np.zeros(5)])

sim = sesi.Simulation(space="hyperbolic", dim=2, radius=1.0, name="five-bodies")
sim.add_bodies(1.0, x=x, v=v)
sim.add_potential("lennard-jones", epsilon=1.0, sigma=0.5, cutoff=1.25)
sim.dt = 0.01
out = sim.run(t_end=20.0, output_every=10)
page = sim.view(out)                          # a sesi.View: the page `sesi view` writes
print(page)                                   # <sesi.View 'five-bodies': H^2, 5 bodies, 201 frames>
path = page.save(os.path.join(tempfile.mkdtemp(), "five-bodies.html"))
print("wrote", path)
