#!/usr/bin/python3
"""Spaces with a topology from Python (docs/python.md, issue #26): a Lennard-Jones liquid in a
periodic box of E^2, its mean-squared displacement from the unwrapped positions, and bodies
crossing the sides of the genus-2 (Bolza) surface of H^2.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/topology.py
"""
import math

import numpy as np

import sesi
import sesi.analysis

# 100 Lennard-Jones bodies on a square lattice of spacing 1.4 in a periodic 14 x 14 box (density
# 0.51), random velocities.
rng = np.random.default_rng(1)
x = 1.4 * (np.stack(np.meshgrid(np.arange(10), np.arange(10)), axis=-1).reshape(-1, 2) + 0.5)
sim = sesi.Simulation(space="euclidean", dim=2, box=[14.0, 14.0])
sim.add_bodies(1.0, x=x, v=rng.normal(0.0, 1.0, x.shape))
sim.add_potential("lennard-jones", epsilon=1.0, sigma=1.0, cutoff=2.5)
sim.method, sim.dt = "sesi4", 0.005
out = sim.run(t_end=5.0, output_every=20)
# In the box, or past a face by less than the wrap margin (a quarter of the cutoff).
print("farthest outside the box:", float(np.maximum(-sim.x, sim.x - 14.0).max(initial=0.0)))
print("bodies that crossed a face:", int((sim.image_counts != 0).any(axis=1).sum()))  # int64 counts
m = sesi.analysis.msd(out["unwrapped_points"], space="euclidean", t=out["t"])
print("MSD at t = 2.5:", m.value[-1])
print("energy drift:", float(out["energy"][-1] - out["energy"][0]))

# The Bolza surface (genus 2) of radius 2: 8 bodies leave the octagon through its sides and come
# back through the paired ones; sim.words says which group element took each back.
radius, d = 2.0, 1.45  # 2.9 from the centre (the octagon's inradius is 3.06)
phi = 2 * np.pi * (np.arange(8) + 0.3) / 8
x = np.column_stack([radius * math.sinh(d) * np.cos(phi), radius * math.sinh(d) * np.sin(phi),
                     np.full(8, radius * math.cosh(d))])
v = np.column_stack([math.cosh(d) * np.cos(phi), math.cosh(d) * np.sin(phi), np.full(8, math.sinh(d))])
sim = sesi.Simulation(space="hyperbolic", dim=2, radius=radius, genus=2)
sim.add_bodies(1.0, x=x, v=v)
sim.add_potential("lennard-jones", epsilon=1.0, sigma=0.5, cutoff=1.25)
sim.dt = 0.005
sim.integrate(1.0)
print("words:", sim.words)                                     # "e" or side numbers, e.g. "1.6"
print("unwrapped body 1:", sim.unwrapped_points[0])           # W_b x_b in the covering H^2
