"""sesi.methods() is the program's machine-readable method list (`sesi run --list-methods --json`),
field for field, and a Simulation runs each method on exactly the spaces it lists."""
import json
import math
import subprocess

import pytest

import sesi


def test_methods_equal_the_programs_list(program):
    r = subprocess.run([program, "run", "--list-methods", "--json"], capture_output=True, text=True)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert sesi.methods() == json.loads(r.stdout)["methods"]
    r = subprocess.run([program, "run", "--list-methods"], capture_output=True, text=True)
    assert r.stdout.splitlines() == [m["name"] for m in sesi.methods()]


def test_families_and_fields():
    for m in sesi.methods():
        assert m["family"] in ("chart", "processed", "geodesic", "reference"), m
        assert m["processed"] == (m["output_stages"] > 0), m
        assert m["name"].startswith("geodesic") == (m["family"] == "geodesic"), m
        assert m["spaces"] == (["sphere", "hyperbolic"] if m["family"] == "geodesic"
                               else ["sphere", "hyperbolic", "euclidean"]), m


@pytest.mark.parametrize("space", ["sphere", "hyperbolic", "euclidean"])
def test_each_method_runs_where_listed(space):
    # Off the charts' singular points (the origin of H^2's chart); v tangent at x.
    x = {"sphere": ([1, 0, 0], [0, 1, 0]), "hyperbolic": ([math.sinh(0.5), 0, math.cosh(0.5)], [0, 0.3, 0]),
         "euclidean": ([0, 0], [1, 0])}[space]
    for m in sesi.methods():
        sim = sesi.Simulation(space=space, dim=2, radius=None if space == "euclidean" else 1.0)
        sim.add_body(mass=1.0, x=x[0], v=x[1])
        sim.method = m["name"]
        sim.dt = 0.01
        if space in m["spaces"]:
            sim.integrate(0.05)
            assert sim.step == 5, (m["name"], space, sim.step)
        else:
            with pytest.raises(sesi.InputError, match=m["name"]):
                sim.integrate(0.05)
