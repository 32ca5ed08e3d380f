"""The Python package's API (issue #13): building, reading, catalogues, states, settings."""
import math

import numpy as np
import pytest

import sesi


def two_bodies(**integrator):
    sim = sesi.Simulation(space="sphere", dim=2, radius=1.0)
    sim.add_body(mass=1.0, x=[1, 0, 0], v=[0, 0.3, 0])
    sim.add_body(mass=1.0, x=[-1, 0, 0], v=[0, -0.3, 0])
    sim.add_potential("harmonic-pair", k=1.0, d0=2.0)
    sim.method = integrator.get("method", "sesi4")
    sim.dt = integrator.get("dt", 0.01)
    return sim


def test_catalogues_name_every_method_and_potential():
    names = [m["name"] for m in sesi.methods()]
    assert names == ["sesi2", "sesi4", "sesi4-suzuki", "sesi4-mclachlan", "sesi6", "sesi6-kahan-li", "sesi8",
                     "sesi8-kahan-li", "sesi6-processed", "sesi8-processed", "sesi10-processed", "geodesic2",
                     "geodesic4", "geodesic6", "geodesic6-kahan-li", "geodesic8", "geodesic8-kahan-li",
                     "geodesic6-processed", "geodesic8-processed", "geodesic10-processed"]
    assert [m["order"] for m in sesi.methods()] == [2, 4, 4, 4, 6, 6, 8, 8, 6, 8, 10, 2, 4, 6, 6, 8, 8, 6, 8, 10]
    kinds = {p["kind"]: p for p in sesi.potentials()}
    assert set(kinds) == {"chord-well", "cotangent-gravity", "central-cotangent", "harmonic-pair", "lennard-jones"}
    assert kinds["lennard-jones"]["keys"] == ["epsilon", "sigma", "cutoff", "min_distance"]


def test_state_arrays_have_one_row_per_body():
    sim = two_bodies()
    assert sim.x.shape == (2, 3) and sim.v.shape == (2, 3)
    assert sim.q.shape == (2, 2) and sim.p.shape == (2, 2)
    np.testing.assert_allclose(sim.x[0], [1, 0, 0], rtol=0, atol=1e-15)  # through the chart: cos(pi/2)
    assert sim.t == 0.0 and sim.n_bodies == 2 and sim.dim == 2 and sim.space == "sphere"
    assert len(sim.momentum_map()) == len(sim.momentum_names) == 3


def test_integrate_ends_at_t_and_conserves():
    sim = two_bodies()
    e0, m0 = sim.energy(), sim.momentum_map()
    sim.integrate(1.234)
    assert sim.t == 1.234
    assert sim.step == 124  # 123 whole steps and a last one of 0.004
    # Bodies stay on the sphere; SESI 4 at dt = 0.01: energy error ~ dt^4 (and a round-off floor).
    np.testing.assert_allclose(np.linalg.norm(sim.x, axis=1), 1.0, rtol=0, atol=64 * np.finfo(float).eps)
    assert abs(sim.energy() - e0) < 1e-7 * (abs(e0) + 1)
    # The splitting keeps the rotation about the chart's polar axis (M1_2) to round-off, the
    # other components to the method's order: dt^4 = 1e-8 times the orbit's scale.
    m = sim.momentum_map()
    assert abs(m[0] - m0[0]) < 64 * np.finfo(float).eps
    np.testing.assert_allclose(m, m0, rtol=0, atol=10 * 0.01 ** 4)


def test_integrate_in_pieces_on_the_grid_equals_one_run():
    a, b = two_bodies(), two_bodies()
    a.integrate(2.0)
    for t in (0.5, 1.0, 1.5, 2.0):
        b.integrate(t)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.p, b.p)
    assert a.step == b.step == 200


def test_run_rows_and_backwards():
    sim = two_bodies(method="sesi2", dt=0.1)
    out = sim.run(t_end=1.0, output_every=2)
    assert list(out) == ["t", "energy", "q", "p", "x", "v", "momentum"]
    np.testing.assert_allclose(out["t"], [0, 0.2, 0.4, 0.6, 0.8, 1.0], atol=1e-15)
    assert out["x"].shape == (6, 2, 3) and out["q"].shape == (6, 2, 2) and out["momentum"].shape == (6, 3)
    np.testing.assert_array_equal(out["x"][-1], sim.x)
    # Time-reversible: back to t = 0 with dt < 0 returns to the start (to round-off).
    sim.dt = -0.1
    sim.integrate(0.0)
    assert sim.t == 0.0
    np.testing.assert_allclose(sim.x, out["x"][0], rtol=0, atol=1e-13)


def test_settings_change_between_runs():
    a, b = two_bodies(method="sesi4"), two_bodies(method="sesi4")
    a.integrate(0.5)
    a.method = "sesi6"
    a.integrate(1.0)
    b.integrate(0.5)
    b.method = "sesi6"
    b.integrate(1.0)
    np.testing.assert_array_equal(a.x, b.x)
    assert a.method == "sesi6"


def test_from_dict_equals_the_builder():
    doc = {
        "space": {"kind": "sphere", "dim": 2, "radius": 1.0},
        "bodies": [{"mass": 1.0, "x": np.array([1.0, 0, 0]), "v": [0, 0.3, 0]},
                   {"mass": 1.0, "x": [-1, 0, 0], "v": [0, -0.3, 0]}],
        "potential": [{"kind": "harmonic-pair", "k": 1.0, "d0": 2.0}],
        "integrator": {"method": "sesi4", "dt": 0.01},
    }
    a = sesi.Simulation.from_dict(doc)
    b = two_bodies()
    a.integrate(1.0)
    b.integrate(1.0)
    np.testing.assert_array_equal(a.x, b.x)


def test_add_bodies_from_arrays():
    phi = np.linspace(0, 2 * math.pi, 5, endpoint=False)
    x = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=1)
    v = np.stack([-np.sin(phi), np.cos(phi), np.zeros_like(phi)], axis=1) * 0.2
    sim = sesi.Simulation(space="sphere", dim=2)
    sim.add_bodies(mass=1.0, x=x, v=v)
    sim.add_potential("cotangent-gravity", G=0.01)
    sim.dt = 0.01
    sim.integrate(0.1)
    assert sim.n_bodies == 5 and sim.x.shape == (5, 3)


def test_paper_scene_is_the_programs_default():
    sim = sesi.Simulation.paper()
    assert sim.method == "sesi4" and sim.dt == 0.1 and sim.n_bodies == 3
    np.testing.assert_allclose(sim.x, sesi.paper_exact(0.0)[0], rtol=0, atol=1e-15)


def test_method_auto_from_a_scene():
    """method = "auto" (issue #15) is resolved when the simulation is made from a scene: the same
    choice as `sesi run`, a method of the catalogue and a step, and the reason."""
    doc = {"space": {"kind": "sphere", "dim": 2, "radius": 1.0},
           "bodies": [{"mass": 1.0, "q": [0.8, 0.0], "p": [0.0, 0.7]}],
           "potential": [{"kind": "central-cotangent", "k": 1.0, "center": [0.0, 0.0, 1.0]}],
           "integrator": {"method": "auto", "tolerance": 1e-8, "t_end": 20.0}}
    sim = sesi.Simulation.from_dict(doc)
    assert sim.method in [m["name"] for m in sesi.methods()]
    assert sim.dt > 0 and sim.auto_reason.startswith(sim.method)
    e0 = sim.energy()
    sim.integrate(20.0)
    assert abs(sim.energy() - e0) <= 10 * 1e-8 * abs(e0)
    with pytest.raises(sesi.InputError, match="auto"):
        sim.method = "auto"
