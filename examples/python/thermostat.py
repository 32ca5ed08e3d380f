#!/usr/bin/python3
"""Thermostats from Python (docs/python.md, docs/thermostats.md): 50 Lennard-Jones bodies on a
sphere of radius 4, equilibrated at kT = 1 with Langevin dynamics, quenched to kT = 0.2 by a
Nose-Hoover chain, then run at constant energy.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/thermostat.py
"""
import numpy as np

import sesi

# 50 bodies on a Fibonacci lattice of the sphere (spacing about 2 sigma), at rest.
n, radius = 50, 4.0
k = np.arange(n) + 0.5
z = 1.0 - 2.0 * k / n
phi = np.pi * (1.0 + 5.0**0.5) * k
x = radius * np.column_stack([np.sqrt(1.0 - z**2) * np.cos(phi), np.sqrt(1.0 - z**2) * np.sin(phi), z])

sim = sesi.Simulation(space="sphere", dim=2, radius=radius)
sim.add_bodies(1.0, x=x, v=np.zeros_like(x))
sim.add_potential("lennard-jones", epsilon=1.0, sigma=1.0, cutoff=2.5)
sim.dt = 0.005

sim.thermostat = sesi.Thermostat("langevin", temperature=1.0, gamma=1.0, seed=3)
sim.run(t_end=50.0, output_every=10)                 # equilibrate at kT = 1
sim.thermostat = {"kind": "nose-hoover", "temperature": [(50.0, 1.0), (150.0, 0.2)], "tau": 0.5}
sim.run(t_end=150.0, output_every=10)                # quench to kT = 0.2
sim.thermostat = None                                # constant energy again

out = sim.run(t_end=160.0, output_every=100)
# The kinetic temperature 2K / N_f with N_f = 2 per body, near the quench's end point kT = 0.2.
v = sim.v
print("kinetic temperature after the quench:", float(np.sum(v * v)) / (2 * n))
print("energy drift at constant energy:", float(out["energy"][-1] - out["energy"][0]))
