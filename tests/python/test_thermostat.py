"""sim.thermostat (docs/python.md, "Thermostats"): set, read back, None; checked by the program's scene
reader with its messages; the method it runs with; a run from Python equals `sesi run` of the same scene
bit for bit, and a run in pieces one run."""
import csv
import re
import subprocess

import numpy as np
import pytest

import sesi

BODIES = """[space]
kind = "sphere"
dim = 2

[[bodies]]
mass = 1.0
x = [1.0, 0.0, 0.0]
v = [0.0, 0.3, 0.0]

[[bodies]]
mass = 2.0
x = [0.0, 1.0, 0.0]
v = [0.0, 0.0, 0.3]

[[bodies]]
mass = 1.0
x = [0.6, 0.0, 0.8]
v = [0.0, 0.2, 0.0]

[[potential]]
kind = "harmonic-pair"
k = 1.0
d0 = 1.0

[integrator]
dt = 0.01
t_end = 0.5
output_every = 5
"""


def three_bodies():
    sim = sesi.Simulation(space="sphere", dim=2)
    sim.add_body(mass=1.0, x=[1.0, 0.0, 0.0], v=[0.0, 0.3, 0.0])
    sim.add_body(mass=2.0, x=[0.0, 1.0, 0.0], v=[0.0, 0.0, 0.3])
    sim.add_body(mass=1.0, x=[0.6, 0.0, 0.8], v=[0.0, 0.2, 0.0])
    sim.add_potential("harmonic-pair", k=1.0, d0=1.0)
    sim.dt = 0.01
    return sim


def test_set_read_back_and_none():
    sim = three_bodies()
    sim.thermostat = sesi.Thermostat("langevin", temperature=0.5, gamma=2.0, seed=3)
    assert sim.method == "sesi2"  # a thermostat's method, when none is given
    assert sim.thermostat == sesi.Thermostat("langevin", temperature=0.5, gamma=2.0, seed=3)
    sim.thermostat = {"kind": "nose-hoover", "temperature": [(0.0, 2.0), (1.0, 0.5)], "tau": 0.5}
    assert sim.thermostat == sesi.Thermostat("nose-hoover", temperature=[(0.0, 2.0), (1.0, 0.5)], tau=0.5, chain=3)
    sim.thermostat = sesi.Thermostat("csvr", temperature=1, tau=0.25)
    assert sim.thermostat.as_dict() == {"kind": "csvr", "temperature": 1.0, "tau": 0.25, "seed": 0}
    sim.thermostat = None
    assert sim.thermostat is None
    assert "thermostat" in repr(sesi.Thermostat("brownian", temperature=1.0, gamma=1.0)).lower()


def test_kinds_listed():
    assert sesi.thermostats() == [{"kind": "langevin", "keys": ["gamma", "seed"]},
                                  {"kind": "nose-hoover", "keys": ["tau", "chain"]},
                                  {"kind": "csvr", "keys": ["tau", "seed"]},
                                  {"kind": "brownian", "keys": ["gamma", "seed"]}]


def test_before_start_goes_into_the_scene():
    sim = three_bodies()
    sim.thermostat = sesi.Thermostat("brownian", temperature=0.2, gamma=4.0, seed=9)
    sim.thermostat = None  # not started yet: back out of the scene
    assert sim.method == "sesi4" and sim.thermostat is None


def program_error(program, tmp_path, table):
    path = tmp_path / "scene.toml"
    path.write_text(BODIES + "\n" + table)
    result = subprocess.run([program, "run", str(path), "--out", str(tmp_path / "out")], capture_output=True, text=True)
    assert result.returncode == 2, result.stderr
    return result.stderr.strip()


@pytest.mark.parametrize("keys, table", [
    (dict(kind="langevin", temperature=1.0, gamma=-1.0),
     '[thermostat]\nkind = "langevin"\ntemperature = 1.0\ngamma = -1.0\n'),
    (dict(kind="nose-hoover", temperature=1.0, tau=1.0, seed=2),
     '[thermostat]\nkind = "nose-hoover"\ntemperature = 1.0\ntau = 1.0\nseed = 2\n'),
    (dict(kind="csvr", temperature=[(0.0, 1.0), (0.0, 2.0)], tau=1.0),
     '[thermostat]\nkind = "csvr"\ntemperature = [[0.0, 1.0], [0.0, 2.0]]\ntau = 1.0\n'),
    (dict(kind="langevn", temperature=1.0, gamma=1.0),
     '[thermostat]\nkind = "langevn"\ntemperature = 1.0\ngamma = 1.0\n'),
    (dict(kind="nose-hoover", temperature=1.0, tau=1.0, chain=0),
     '[thermostat]\nkind = "nose-hoover"\ntemperature = 1.0\ntau = 1.0\nchain = 0\n'),
])
def test_the_programs_messages(program, tmp_path, keys, table):
    """The same checks and words as sesi run (after the key; the place differs: a file's line, <simulation>)."""
    expected = re.sub(r"^sesi: error: \S+:\d+:\d+: ", "", program_error(program, tmp_path, table))
    for started in (False, True):
        sim = three_bodies()
        if started:
            sim.thermostat = sesi.Thermostat("langevin", temperature=1.0, gamma=1.0)
            sim.integrate(0.02)
        with pytest.raises(sesi.InputError) as error:
            sim.thermostat = keys
        assert str(error.value).endswith(expected), (str(error.value), expected)
        if started:  # the simulation goes on with the thermostat it had
            assert sim.thermostat == sesi.Thermostat("langevin", temperature=1.0, gamma=1.0, seed=0)


def test_only_with_sesi2():
    sim = three_bodies()
    sim.method = "sesi4"
    sim.integrate(0.02)
    with pytest.raises(sesi.InputError, match='runs with method "sesi2"'):
        sim.thermostat = sesi.Thermostat("langevin", temperature=1.0, gamma=1.0)
    assert sim.thermostat is None
    sim.method = "sesi2"
    sim.thermostat = sesi.Thermostat("langevin", temperature=1.0, gamma=1.0)
    with pytest.raises(sesi.InputError, match='runs with method "sesi2"'):
        sim.method = "sesi4"
    assert sim.method == "sesi2"
    with pytest.raises(sesi.InputError, match="expected a sesi.Thermostat"):
        sim.thermostat = "langevin"


def program_rows(program, scene, out):
    subprocess.run([program, "run", str(scene), "--out", str(out), "--quiet"], check=True, capture_output=True)
    with open(out / "trajectory.csv") as f:
        return list(csv.DictReader(f))


@pytest.mark.parametrize("table", [
    '[thermostat]\nkind = "langevin"\ntemperature = 0.5\ngamma = 2.0\nseed = 3\n',
    '[thermostat]\nkind = "nose-hoover"\ntemperature = [[0.0, 1.0], [0.3, 0.2]]\ntau = 0.2\n',
    '[thermostat]\nkind = "csvr"\ntemperature = 0.5\ntau = 0.1\nseed = 5\n',
    '[thermostat]\nkind = "brownian"\ntemperature = 0.5\ngamma = 20.0\nseed = 4\n',
])
def test_same_numbers_as_sesi_run(program, tmp_path, table):
    scene = tmp_path / "scene.toml"
    scene.write_text(BODIES + "\n" + table)
    rows = program_rows(program, scene, tmp_path / "out")
    x = np.array([[[float(r[f"b{b + 1}_x{i + 1}"]) for i in range(3)] for b in range(3)] for r in rows])
    # A scene file read by Python, and the same scene built in Python, in two pieces.
    sim = sesi.Simulation.from_toml(str(scene))
    out = sim.run(t_end=0.5, output_every=5)
    np.testing.assert_array_equal(out["x"], x)
    built = three_bodies()
    built.thermostat = sesi.Simulation.from_toml(str(scene)).thermostat
    first = built.run(t_end=0.2, output_every=5)
    second = built.run(t_end=0.5, output_every=5)
    np.testing.assert_array_equal(np.concatenate([first["x"], second["x"][1:]]), x)


def test_example_runs(source_dir):
    # examples/python/thermostat.py, whose lines docs/python.md shows: equilibrate, quench, NVE.
    import sys
    r = subprocess.run([sys.executable, str(source_dir / "examples" / "python" / "thermostat.py")],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    kinetic = float(re.search(r"kinetic temperature after the quench: (\S+)", r.stdout).group(1))
    # 50 bodies, N_f = 100: one reading of 2K/N_f has a relative spread of sqrt(2 / N_f) = 0.14 about the
    # quench's kT = 0.2 (more after 10 time units at constant energy); 5 spreads: a wrong quench
    # (kT 1 kept, or frozen at 0) is far outside.
    assert abs(kinetic - 0.2) < 5 * 0.2 * (2 / 100) ** 0.5
