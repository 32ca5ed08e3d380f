#!/usr/bin/python3
"""The Python package's first example (README.md, docs/python.md): two bodies under cotangent
gravity on the unit sphere S^2, SESI 4, with the energy and angular momentum they keep.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/quickstart.py
"""
import sesi

sim = sesi.Simulation(space="sphere", dim=2, radius=1.0)
sim.add_body(mass=1.0, x=[1, 0, 0], v=[0, 0.3, 0])
sim.add_body(mass=0.5, x=[0, 1, 0], v=[-0.3, 0, 0.1])
sim.add_potential("cotangent-gravity", G=0.1)
sim.method = "sesi4"
sim.dt = 0.01
e0 = sim.energy()
sim.integrate(10.0)
print(sim.t, sim.x[0], sim.energy() - e0)

out = sim.run(t_end=20.0, output_every=100)  # rows of t, x, v, q, p, energy, momentum
print(out["t"], out["energy"] - e0)
