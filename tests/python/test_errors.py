"""Bad input raises sesi.InputError (a ValueError) with the program's one-line message; a failed
check raises sesi.InstabilityError and leaves the simulation at its last good state."""
import math

import numpy as np
import pytest

import sesi


def sphere():
    sim = sesi.Simulation(space="sphere", dim=2)
    sim.add_body(mass=1.0, x=[1, 0, 0], v=[0, 0.1, 0])
    return sim


def test_input_error_is_a_value_error():
    assert issubclass(sesi.InputError, ValueError)
    assert issubclass(sesi.InstabilityError, RuntimeError)


@pytest.mark.parametrize("build, words", [
    (lambda s: s.add_body(mass=-1.0, x=[0, 1, 0]), ["bodies[2].mass", "> 0"]),
    (lambda s: s.add_body(mass=1.0, x=[0, 2, 0]), ["bodies[2].x", "not on the sphere"]),
    (lambda s: s.add_body(mass=1.0, x=[0, 1, 0], v=[0, 1, 0]), ["bodies[2].v", "tangent"]),
    (lambda s: s.add_body(mass=1.0, x=[0, 1, 0], q=[0.1, 0.2]), ["bodies[2]"]),
    (lambda s: s.add_potential("lennard-jone"), ["potential[1].kind", "did you mean 'lennard-jones'"]),
    (lambda s: s.add_potential("harmonic-pair", kk=1.0), ["potential[1]", "kk", "k"]),
    (lambda s: s.add_potential("harmonic-pair", k="one"), ["potential[1].k"]),
    (lambda s: s.add_potential("central-cotangent"), ["potential[1].center", "missing"]),
])
def test_bad_scene_values_name_the_key(build, words):
    sim = sphere()
    build(sim)
    with pytest.raises(sesi.InputError) as e:
        sim.integrate(0.0)
    message = str(e.value)
    assert "\n" not in message
    for w in words:
        assert w in message, f"{w!r} not in {message!r}"


def test_bad_settings():
    sim = sphere()
    sim.dt = 0.1
    sim.integrate(0.1)
    with pytest.raises(sesi.InputError, match="method"):
        sim.method = "sesi3"
    with pytest.raises(sesi.InputError, match="dt"):
        sim.dt = 0.0
    with pytest.raises(sesi.InputError, match="before the simulation's time"):
        sim.integrate(0.0)
    with pytest.raises(sesi.InputError, match="started"):
        sim.add_body(mass=1.0, x=[0, 1, 0])
    with pytest.raises(sesi.InputError, match="finite"):
        sim.integrate(math.inf)
    with pytest.raises(sesi.InputError, match="output_every"):
        sim.run(1.0, output_every=0)
    assert sim.t == 0.1  # nothing moved


def test_bad_documents():
    with pytest.raises(sesi.InputError, match=r"<dict>: spaec: unknown key .*did you mean 'space'"):
        sesi.Simulation.from_dict({"spaec": {"kind": "sphere", "dim": 2}})
    with pytest.raises(sesi.InputError, match="bodies"):
        sesi.Simulation.from_dict({"space": {"kind": "sphere", "dim": 2}})
    with pytest.raises(sesi.InputError, match="not a scene value"):
        sesi.Simulation.from_dict({"space": {"kind": "sphere", "dim": 2}, "bodies": [{"mass": object()}]})
    with pytest.raises(sesi.InputError, match="cannot read the scene file"):
        sesi.Simulation.from_toml("/nonexistent/scene.toml")
    with pytest.raises(sesi.InputError, match="no step size"):
        sphere().integrate(1.0)


def test_toml_errors_name_file_and_line(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('[space]\nkind = "sphere"\ndim = 2\n\n[[bodies]]\nmass = 0\nq = [1.0, 0.0]\n')
    with pytest.raises(sesi.InputError, match=r"bad.toml:6.*bodies\[1\]\.mass"):
        sesi.Simulation.from_toml(str(path))


def collision(**guard):
    # Two bodies on a great circle falling into each other under cotangent gravity: they meet
    # near t = 0.35 and the close-encounter floor stops the run.
    sim = sesi.Simulation(space="sphere", dim=2)
    sim.add_body(mass=1.0, x=[1, 0, 0])
    sim.add_body(mass=1.0, x=[math.cos(0.3), math.sin(0.3), 0])
    sim.add_potential("cotangent-gravity", G=1.0, min_distance=1e-3)
    sim.dt = 1e-3
    for key, value in guard.items():
        setattr(sim, key, value)
    return sim


def test_close_encounter_raises_and_keeps_the_last_good_state():
    sim = collision()
    with pytest.raises(sesi.InstabilityError) as e:
        sim.run(t_end=5.0, output_every=10)
    err = e.value
    assert err.reason == "close encounter"
    assert "bodies 1 and 2" in str(err) and f"step {err.step}" in str(err)
    assert 0 < sim.t < err.t and sim.step == err.step - 1  # checked every step below 1000 bodies
    assert np.isfinite(sim.energy())
    gap = np.arccos(np.clip(np.dot(sim.x[0], sim.x[1]), -1, 1))
    assert gap >= 1e-3
    # The rows up to the failure come with it; the last is the last good state.
    np.testing.assert_array_equal(err.output["x"][-1], sim.x)


def test_energy_guard_raises():
    sim = collision(energy_guard=1e-6)
    with pytest.raises(sesi.InstabilityError, match="energy error exceeded") as e:
        sim.integrate(5.0)
    assert e.value.reason == "energy error exceeded"
    assert np.isfinite(sim.energy())
