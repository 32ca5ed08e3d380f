"""The package against the program: the same scene file gives the same numbers to the bit as
`sesi run`; Ctrl-C, the GIL, Python potentials, and the examples under examples/python/."""
import csv
import math
import os
import subprocess
import sys
import threading

import numpy as np
import pytest

import sesi


def program_rows(program, scene, out, t_end):
    subprocess.run([program, "run", str(scene), "--out", str(out), "--t-end", str(t_end), "--quiet"], check=True,
                   capture_output=True)
    with open(out / "trajectory.csv") as f:
        rows = list(csv.DictReader(f))
    return rows


def columns(rows, kind, bodies, count):
    return np.array([[[float(r[f"b{b + 1}_{kind}{i + 1}"]) for i in range(count)] for b in range(bodies)]
                     for r in rows])


@pytest.mark.parametrize("scene, t_end", [
    ("paper.toml", 20.0),
    ("sphere-pole-crossing.toml", 3.0),
    ("sphere-two-body-xv.toml", 2.0),
    ("hyperbolic-kepler-xv.toml", 2.0),
    ("euclidean-figure-eight-qp.toml", 2.0),
])
def test_same_numbers_as_sesi_run(program, source_dir, tmp_path, scene, t_end):
    path = source_dir / "examples" / "scenes" / scene
    rows = program_rows(program, path, tmp_path / "out", t_end)
    sim = sesi.Simulation.from_toml(str(path))
    out = sim.run(t_end=t_end, output_every=sim._core.output_every)
    n, dim = sim.n_bodies, sim.dim
    ambient = out["x"].shape[2]
    np.testing.assert_array_equal(out["t"], [float(r["t"]) for r in rows])
    np.testing.assert_array_equal(out["q"], columns(rows, "q", n, dim))
    np.testing.assert_array_equal(out["p"], columns(rows, "p", n, dim))
    np.testing.assert_array_equal(out["x"], columns(rows, "x", n, ambient))


def test_a_run_in_pieces_gives_the_programs_numbers(program, source_dir, tmp_path):
    path = source_dir / "examples" / "scenes" / "sphere-two-body-qp.toml"
    rows = program_rows(program, path, tmp_path / "out", 2.0)
    sim = sesi.Simulation.from_toml(str(path))
    every = sim._core.output_every
    sim.integrate(1.0)  # on the grid of dt
    out = sim.run(t_end=2.0, output_every=every)
    np.testing.assert_array_equal(out["x"][-1], columns(rows[-1:], "x", sim.n_bodies, 3)[0])


def test_python_potential_matches_the_built_in_one():
    # central-cotangent on the unit S^2: V = -k m cot d, cos d = x . c; dV/dx = -k m c / (1 - u^2)^(3/2).
    center = np.array([0.0, 0.0, 1.0])
    k = 0.5

    def value(x, m):
        u = float(x @ center)
        return -k * m * u / math.sqrt(1 - u * u)

    def gradient(x, m):
        u = float(x @ center)
        return -k * m * center / (1 - u * u) ** 1.5

    def sim_with(potential):
        sim = sesi.Simulation(space="sphere", dim=2)
        sim.add_body(mass=1.0, x=[1, 0, 0], v=[0, 0.8, 0.1])
        sim.add_body(mass=2.0, x=[0, -0.6, -0.8], v=[0.5, 0, 0])
        potential(sim)
        sim.dt = 0.01
        return sim

    built_in = sim_with(lambda s: s.add_potential("central-cotangent", k=k, center=center))
    python = sim_with(lambda s: s.add_potential(value=value, gradient=gradient))
    assert python.energy() == pytest.approx(built_in.energy(), rel=1e-14)
    built_in.integrate(2.0)
    python.integrate(2.0)
    # Two formulas of one force: round-off apart, grown over 200 steps of a smooth orbit.
    np.testing.assert_allclose(python.x, built_in.x, rtol=0, atol=1e-11)


def test_python_potential_errors_come_back():
    sim = sesi.Simulation(space="sphere", dim=2)
    sim.add_body(mass=1.0, x=[1, 0, 0], v=[0, 0.3, 0])
    sim.add_potential(value=lambda x, m: 0.0, gradient=lambda x, m: np.zeros(2))  # wrong size
    sim.dt = 0.1
    with pytest.raises(sesi.InputError, match="returned 2 values for a point of 3"):
        sim.integrate(1.0)
    assert sim.t == 0.0

    def broken(x, m):
        raise ZeroDivisionError("in the user's potential")

    sim = sesi.Simulation(space="sphere", dim=2)
    sim.add_body(mass=1.0, x=[1, 0, 0], v=[0, 0.3, 0])
    sim.add_potential(value=lambda x, m: 0.0, gradient=broken)
    sim.dt = 0.1
    with pytest.raises(ZeroDivisionError, match="user's potential"):
        sim.integrate(1.0)
    assert sim.t == 0.0


def test_ctrl_c_stops_between_steps():
    script = """
import os, signal, threading, time
import sesi
sim = sesi.Simulation.paper()
sim.dt = 1e-4
threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
start = time.monotonic()
try:
    sim.integrate(1e6)
    print("not interrupted")
except KeyboardInterrupt:
    print("interrupted", sim.step, sim.t, time.monotonic() - start, sim.energy())
"""
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    words = r.stdout.split()
    assert words[0] == "interrupted", r.stdout
    step, t, seconds, energy = int(words[1]), float(words[2]), float(words[3]), float(words[4])
    assert step > 0 and t == pytest.approx(step * 1e-4) and seconds < 5 and math.isfinite(energy)


def test_the_gil_is_released_while_integrating():
    sim = sesi.Simulation.paper()
    sim.dt = 1e-4
    ticks = 0
    done = threading.Event()

    def work():
        sim.integrate(20.0)
        done.set()

    thread = threading.Thread(target=work)
    thread.start()
    while not done.is_set():
        ticks += 1
        done.wait(0.001)
    thread.join()
    assert ticks > 10  # the main thread ran while the other integrated


def test_examples_run(source_dir, tmp_path, program):
    env = dict(os.environ)
    r = subprocess.run([sys.executable, str(source_dir / "examples" / "python" / "quickstart.py")],
                       capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    figure = tmp_path / "seed-figure.png"
    r = subprocess.run([sys.executable, str(source_dir / "examples" / "python" / "seed_figure.py"),
                        "--t-end", "50", "--out", str(figure)], capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr
    assert figure.stat().st_size > 10000


def test_h5md_example_reads_the_programs_trajectory(source_dir, tmp_path, program):
    pytest.importorskip("h5py")
    scene = source_dir / "examples" / "scenes" / "sphere-pole-crossing.toml"
    r = subprocess.run([program, "run", str(scene), "--trajectory-format", "h5md", "--quiet"], cwd=tmp_path,
                       capture_output=True, text=True)
    if r.returncode == 2 and "h5md" in r.stderr:
        pytest.skip("sesi built without HDF5")
    assert r.returncode == 0, r.stderr
    r = subprocess.run([sys.executable, str(source_dir / "examples" / "python" / "read_h5md.py")], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "(" in r.stdout
