"""Spaces with a topology from Python (docs/python.md, "Periodic boxes and compact surfaces"): a periodic
box on E^n (Simulation(space="euclidean", box=[...])) and a compact surface H^2/Gamma of genus g
(Simulation(space="hyperbolic", genus=g)). The scene keys are checked by the program's scene reader with
its messages; sim.x is in the domain (up to the wrap margin), sim.image_counts / sim.words / sim.unwrapped_points say where the
bodies went; a run equals `sesi run` of the same scene bit for bit (trajectory.csv's columns), in one
piece or several, on any number of threads."""
import csv
import math
import random
import re
import subprocess

import numpy as np
import pytest

import sesi

# ---- scenes ------------------------------------------------------------------------------------

BOX = [6.0, 5.0]


def box_bodies(seed=2):
    """20 bodies on a 5 x 4 lattice (spacing 1.2, 1.25) of the 6 x 5 box, drifting together at
    (1.5, -1) (the total momentum is conserved) with random velocities of deviation 0.5 about it:
    by t = 1 the outer columns and rows, 0.6 from a face, have crossed it by more than the wrap
    margin (0.31) both ways: counts of either sign."""
    rng = random.Random(seed)
    x = [[0.6 + 1.2 * i, 0.625 + 1.25 * j] for i in range(5) for j in range(4)]
    v = [[1.5 + rng.gauss(0, 0.5), -1.0 + rng.gauss(0, 0.5)] for _ in x]
    return x, v


R = 2.0  # the surface's radius: genus 2's inradius is R arccosh(cot(pi/8)) = 3.06 (Sausset & Tarjus 2007)


def surface_bodies():
    """8 bodies on the circle of radius 2.9 about the polygon's centre (inside the genus-2 octagon,
    whose inradius is 3.06 at R = 2), moving outwards at unit speed: each leaves through a side
    and, once past it by the wrap margin (a quarter of the cutoff, 0.31), within t = 0.6, comes
    back through the paired one; and two bodies near the centre 0.6 apart (sigma = 0.5): a pair force. Embedding points (x1, x2, x0) on x1^2 + x2^2 - x0^2 = -R^2
    and tangent velocities (Minkowski product with x zero)."""
    x, v = [], []
    for k in range(8):
        phi, d = 2 * math.pi * (k + 0.3) / 8, 2.9 / R  # off the sides' midpoints and the vertices
        x.append([R * math.sinh(d) * math.cos(phi), R * math.sinh(d) * math.sin(phi), R * math.cosh(d)])
        v.append([math.cosh(d) * math.cos(phi), math.cosh(d) * math.sin(phi), math.sinh(d)])
    for s in (-0.3, 0.3):
        x.append([s, 0.0, math.sqrt(R * R + s * s)])
        v.append([0.0, 0.2 * s, 0.0])
    return x, v


def toml_value(value):
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(float(c)) for c in value) + "]"
    return repr(value)


def scene_text(space, bodies, potential, integrator):
    """A scene file: the tables' keys, each body's x and v written exactly (repr)."""
    lines = ["[space]"] + [f"{k} = {toml_value(v)}" for k, v in space.items()]
    for x, v in zip(*bodies):
        lines += ["", "[[bodies]]", "mass = 1.0", f"x = {toml_value(x)}", f"v = {toml_value(v)}"]
    lines += ["", "[[potential]]"] + [f"{k} = {toml_value(v)}" for k, v in potential.items()]
    lines += ["", "[integrator]"] + [f"{k} = {toml_value(v)}" for k, v in integrator.items()]
    return "\n".join(lines) + "\n"


BOX_SPACE = {"kind": "euclidean", "dim": 2, "box": BOX}
SURFACE_SPACE = {"kind": "hyperbolic", "dim": 2, "radius": R, "genus": 2}
LJ = {"kind": "lennard-jones", "epsilon": 1.0, "sigma": 0.5, "cutoff": 1.25}
INTEGRATOR = {"method": "sesi4", "dt": 0.005, "t_end": 1.0, "output_every": 20}


def built(space, bodies):
    """The same scene built in Python (the constructor's box= / genus=)."""
    keys = {k: v for k, v in space.items() if k != "kind"}
    sim = sesi.Simulation(space=space["kind"], **keys)
    x, v = bodies
    sim.add_bodies(1.0, x=np.array(x), v=np.array(v))
    sim.add_potential(**LJ)
    sim.method, sim.dt = INTEGRATOR["method"], INTEGRATOR["dt"]
    return sim


def program_rows(program, scene, out, *args):
    subprocess.run([program, "run", str(scene), "--out", str(out), "--quiet", *args], check=True, capture_output=True)
    with open(out / "trajectory.csv") as f:
        return list(csv.DictReader(f))


def columns(rows, bodies, name, count, kind=float):
    return np.array([[[kind(r[f"b{b + 1}_{name}{i + 1}"]) for i in range(count)] for b in range(bodies)] for r in rows])


# ---- a periodic box ----------------------------------------------------------------------------

def test_box_run_equals_sesi_run(program, tmp_path):
    scene = tmp_path / "box.toml"
    bodies = box_bodies()
    scene.write_text(scene_text(BOX_SPACE, bodies, LJ, INTEGRATOR))
    rows = program_rows(program, scene, tmp_path / "out")
    n = len(bodies[0])
    x, counts = columns(rows, n, "x", 2), columns(rows, n, "n", 2, int)
    # Bodies crossed faces, both ways (else the image columns test nothing).
    assert counts.min() < 0 < counts.max(), (counts.min(), counts.max())
    for sim in (sesi.Simulation.from_toml(str(scene)), built(BOX_SPACE, bodies)):
        out = sim.run(t_end=0.5, output_every=20)
        more = sim.run(t_end=1.0, output_every=20)  # in two pieces: the steps, and the counts, of one run
        for key in ("x", "image_counts", "unwrapped_points"):
            out[key] = np.concatenate([out[key], more[key][1:]])
        np.testing.assert_array_equal(out["x"], x)
        assert out["image_counts"].dtype == np.int64 and out["image_counts"].shape == x.shape
        np.testing.assert_array_equal(out["image_counts"], counts)
        # Unwrapped: x + L n, exact in the counts (one product and one sum, rounded once each).
        np.testing.assert_array_equal(out["unwrapped_points"], x + np.array(BOX) * counts)
        np.testing.assert_array_equal(sim.image_counts, counts[-1])
        np.testing.assert_array_equal(sim.unwrapped_points, out["unwrapped_points"][-1])
        assert sim.box == BOX and sim.genus is None and sim.words is None
        assert sim.max_cutoff == min(BOX) / 2  # half the shortest edge, exactly
        assert "words" not in out


def test_box_positions_are_in_the_domain_and_reduced_at_the_start():
    sim = sesi.Simulation(space="euclidean", dim=2, box=BOX)
    # Given outside the box, by more than one edge: reduced into [0, L) with counts 0 (the scene's
    # start is where the counts start).
    sim.add_body(mass=1.0, x=[-0.5, 11.0], v=[1.0, 0.0])
    sim.add_body(mass=1.0, x=[3.0, 2.5], v=[0.0, 0.0])
    sim.add_potential(**LJ)
    sim.dt = 0.01
    np.testing.assert_allclose(sim.x[0], [5.5, 1.0], rtol=0, atol=1e-15)  # -0.5 + 6, 11 - 2 * 5: one rounding at most
    np.testing.assert_array_equal(sim.image_counts, [[0, 0], [0, 0]])
    np.testing.assert_array_equal(sim.unwrapped_points, sim.x)
    sim.integrate(1.0)  # body 1 moves 1.0 along x from 5.5: past the face at 6 by 0.5, more than the wrap margin
    assert sim.image_counts[0].tolist() == [1, 0]
    np.testing.assert_allclose(sim.x[0], [0.5, 1.0], rtol=0, atol=1e-12)  # bound: as the unwrapped point's, below
    # Free flight: the unwrapped point is the straight line (5.5 + t, 1), to the steps' rounding:
    # sesi4's 4 drifts a step, 100 steps, each sum rounded by at most half an ulp of a number below 8
    # (4.4e-16): 400 * 4.4e-16 = 1.8e-13.
    np.testing.assert_allclose(sim.unwrapped_points[0], [6.5, 1.0], rtol=0, atol=1e-12)


def test_threads_give_the_same_bits():
    results = []
    for threads in (1, 2):
        sim = built(BOX_SPACE, box_bodies(seed=5))
        sim.threads = threads
        out = sim.run(t_end=0.5, output_every=50)
        results.append((out["x"], out["image_counts"]))
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1], results[1][1])


# ---- a compact hyperbolic surface -------------------------------------------------------------

def test_surface_run_equals_sesi_run(program, tmp_path):
    scene = tmp_path / "surface.toml"
    bodies = surface_bodies()
    scene.write_text(scene_text(SURFACE_SPACE, bodies, LJ, INTEGRATOR))
    rows = program_rows(program, scene, tmp_path / "out")
    n = len(bodies[0])
    x, u = columns(rows, n, "x", 3), columns(rows, n, "u", 3)
    words = [[r[f"b{b + 1}_word"] for b in range(n)] for r in rows]
    # The ring left through the sides (words other than the identity), the pair at the centre did not.
    assert all(w != "e" for w in words[-1][:8]) and words[-1][8:] == ["e", "e"], words[-1]
    for sim in (sesi.Simulation.from_toml(str(scene)), built(SURFACE_SPACE, bodies)):
        out = sim.run(t_end=0.5, output_every=20)
        more = sim.run(t_end=1.0, output_every=20)
        np.testing.assert_array_equal(np.concatenate([out["x"], more["x"][1:]]), x)
        np.testing.assert_array_equal(np.concatenate([out["unwrapped_points"], more["unwrapped_points"][1:]]), u)
        assert out["words"] + more["words"][1:] == words
        assert sim.words == words[-1] and all(isinstance(w, str) for w in sim.words)
        np.testing.assert_array_equal(sim.unwrapped_points, u[-1])
        assert sim.genus == 2 and sim.box is None and sim.image_counts is None
        # The injectivity radius, half the systole 2 R arccosh(1 + sqrt 2) of the Bolza surface (Sausset &
        # Tarjus 2007), to the rounding of a few products of the generators' entries (cot^4(pi/8) = 34).
        assert sim.max_cutoff == pytest.approx(R * math.acosh(1 + math.sqrt(2)), rel=1e-12)
        assert "image_counts" not in out


def test_surface_free_flight_unwrapped_is_the_geodesic():
    """The ring flies freely (2.9 - 0.3 from the centre pair, farther than the cutoff, and its bodies 3.2
    apart along the circle): its unwrapped points are the radial geodesics of H^2,
    R (sinh(s / R) cos phi, sinh(s / R) sin phi, cosh(s / R)) with s = 2.9 + t, across the sides (Sausset &
    Tarjus 2007: the group element takes the point back to the covering space)."""
    sim = built(SURFACE_SPACE, surface_bodies())
    assert sim.words == ["e"] * 10
    sim.integrate(1.0)
    assert all(w != "e" for w in sim.words[:8]), sim.words
    for w in sim.words:  # "e" or 1-based side numbers 1..4g joined by '.'
        assert w == "e" or all(1 <= int(letter) <= 8 for letter in w.split(".")), w
    d = (2.9 + 1.0) / R
    phi = 2 * np.pi * (np.arange(8) + 0.3) / 8
    geodesic = R * np.column_stack([math.sinh(d) * np.cos(phi), math.sinh(d) * np.sin(phi), np.full(8, math.cosh(d))])
    # Rounding only (each sub-flow of the kinetic hierarchy is exact): 200 steps x 4 drifts x eps x |x| (< 10):
    # 2e-12; one wrap a body, whose gamma F cancels terms of |F| |y| ~ 10 x 10 against |x|: 1e2 eps x 10 =
    # 2e-12. Together 4e-12.
    np.testing.assert_allclose(sim.unwrapped_points[:8], geodesic, rtol=0, atol=1e-11)
    # The wrapped points came back through the paired sides, moving inwards: nearer the centre than the
    # geodesic's 3.9.
    assert (sim.x[:8, 2] < sim.unwrapped_points[:8, 2]).all(), (sim.x[:8], sim.unwrapped_points[:8])


# ---- the program's checks and messages -----------------------------------------------------------

def one_body(space):
    """A body at rest at a valid point of the space (so that the space's keys are what is wrong)."""
    if space["kind"] == "euclidean":
        return [0.1, 0.2], [0.0, 0.0]
    if space["kind"] == "sphere":
        return [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    radius = space.get("radius", 1.0)
    return [0.1, 0.2, math.sqrt(radius * radius + 0.05)], [0.0, 0.0, 0.0]


def program_error(program, tmp_path, space, potential):
    path = tmp_path / "scene.toml"
    x, v = one_body(space)
    path.write_text(scene_text(space, ([x], [v]), potential, INTEGRATOR))
    result = subprocess.run([program, "run", str(path), "--out", str(tmp_path / "out")], capture_output=True,
                            text=True)
    assert result.returncode == 2, result.stderr
    assert not (tmp_path / "out").exists()
    return re.sub(r"^sesi: error: \S+:\d+:\d+: ", "", result.stderr.strip())


@pytest.mark.parametrize("space, potential", [
    ({"kind": "sphere", "dim": 2, "box": [4.0, 4.0]}, LJ),                 # a box off E^n
    ({"kind": "euclidean", "dim": 2, "box": [4.0, 4.0, 4.0]}, LJ),         # the wrong number of edges
    ({"kind": "euclidean", "dim": 2, "box": [4.0, 0.0]}, LJ),              # an edge <= 0
    ({"kind": "euclidean", "dim": 2, "box": [4.0, 2.0]}, LJ),              # cutoff 1.25 > 2 / 2
    ({"kind": "euclidean", "dim": 2, "genus": 2}, LJ),                      # a genus off H^2
    ({"kind": "hyperbolic", "dim": 2, "radius": R, "genus": 1}, LJ),       # genus < 2
    ({"kind": "hyperbolic", "dim": 2, "radius": 0.5, "genus": 2}, LJ),     # cutoff above the surface's largest
])
def test_the_programs_messages(program, tmp_path, space, potential):
    """The same checks and words as sesi run (after the place: a file's line there, <simulation> here)."""
    expected = program_error(program, tmp_path, space, potential)
    keys = {k: v for k, v in space.items() if k != "kind"}
    sim = sesi.Simulation(space=space["kind"], **keys)
    x, v = one_body(space)
    sim.add_body(mass=1.0, x=x, v=v)
    sim.add_potential(**potential)
    with pytest.raises(sesi.InputError) as error:
        sim.energy()
    assert str(error.value).endswith(expected), (str(error.value), expected)
    assert isinstance(error.value, ValueError)


def test_from_dict_with_a_box():
    """from_dict: the scene format's keys, a box given as a NumPy array."""
    x, v = box_bodies()
    sim = sesi.Simulation.from_dict({"space": {"kind": "euclidean", "dim": 2, "box": np.array(BOX)},
                                     "bodies": [{"mass": 1.0, "x": xi, "v": vi} for xi, vi in zip(x, v)],
                                     "potential": [LJ], "integrator": {"method": "sesi2", "dt": 0.01}})
    assert sim.box == BOX
    assert sim.image_counts.shape == (20, 2)
    assert "euclidean 2, box [6.0, 5.0], 20 bodies" in repr(sim), repr(sim)


def test_python_potentials_and_other_methods_refused():
    """An external term (a Python potential: a force centre has images too) and a method that is not a
    chart composition are refused on a topology, as the scene reader refuses them in a file."""
    sim = sesi.Simulation(space="euclidean", dim=2, box=BOX)
    sim.add_body(mass=1.0, x=[1.0, 1.0], v=[0.0, 0.0])
    sim.add_potential(value=lambda x, m: 0.0, gradient=lambda x, m: np.zeros(2))
    with pytest.raises(sesi.InputError, match=r"potential\[1\]\.kind: .*external term"):
        sim.energy()
    sim = built(BOX_SPACE, box_bodies())
    sim.integrate(0.5)
    processed = next(m["name"] for m in sesi.methods() if m["processed"])
    with pytest.raises(sesi.InputError, match="not processed"):
        sim.method = processed
    assert sim.method == "sesi4"
    # Another chart composition, and a thermostat, go on from the same state with its image counts.
    counts, unwrapped = sim.image_counts, sim.unwrapped_points
    assert np.abs(counts).sum() > 0  # else the check below would hold for counts reset to zero
    sim.method = "sesi2"
    sim.thermostat = sesi.Thermostat("langevin", temperature=1.0, gamma=1.0, seed=3)
    np.testing.assert_array_equal(sim.image_counts, counts)
    np.testing.assert_array_equal(sim.unwrapped_points, unwrapped)
    sim.integrate(0.6)
    assert sim.step == 120


def test_example_runs_and_docs_show_its_lines(source_dir):
    """examples/python/topology.py runs (a box liquid's MSD, words on the Bolza surface), and every line of
    docs/python.md's topology example is a line of it."""
    import sys
    example = source_dir / "examples" / "python" / "topology.py"
    r = subprocess.run([sys.executable, str(example)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    outside = float(re.search(r"farthest outside the box: (\S+)", r.stdout).group(1))
    assert outside <= 0.25 * 2.5, outside  # the wrap margin: a quarter of the cutoff
    assert int(re.search(r"bodies that crossed a face: (\d+)", r.stdout).group(1)) > 0, r.stdout
    words = re.search(r"words: (\[.*\])", r.stdout).group(1)
    assert "'e'" not in words, words  # each of the 8 bodies left the octagon and came back
    msd = float(re.search(r"MSD at t = 2.5: (\S+)", r.stdout).group(1))
    assert 0.0 < msd < math.inf  # a number (the MSD's own tests are tests/python/test_analysis.py's)
    text = (source_dir / "docs" / "python.md").read_text()
    block = text.split("## Periodic boxes and compact surfaces", 1)[1].split("```python", 1)[1].split("```", 1)[0]
    lines = {line.strip() for line in example.read_text().splitlines()}
    missing = [line for line in block.splitlines() if line.strip() and line.strip() not in lines]
    assert not missing, missing


@pytest.mark.parametrize("scene", ["bulk-lj-flat.toml", "bulk-lj-bolza.toml"])
def test_bulk_liquid_equals_sesi_run_on_two_threads(program, source_dir, tmp_path, scene):
    """400 Lennard-Jones bodies in the example box and on the example Bolza surface (examples/scenes,
    docs/topology.md): the neighbour lists across faces and sides, 2 threads in Python against sesi run
    --threads 1, to the bit, over 400 steps (in which some bodies are brought back into the domain)."""
    path = source_dir / "examples" / "scenes" / scene
    rows = program_rows(program, path, tmp_path / "out", "--t-end", "2.0", "--output-every", "100", "--threads", "1")
    sim = sesi.Simulation.from_toml(str(path))
    sim.threads = 2
    out = sim.run(t_end=2.0, output_every=100)
    n, ambient = sim.n_bodies, out["x"].shape[2]
    np.testing.assert_array_equal(out["x"], columns(rows, n, "x", ambient))
    if sim.box is not None:
        np.testing.assert_array_equal(out["image_counts"], columns(rows, n, "n", sim.dim, int))
        moved = int((out["image_counts"][-1] != 0).any(axis=1).sum())
    else:
        np.testing.assert_array_equal(out["unwrapped_points"], columns(rows, n, "u", ambient))
        assert out["words"] == [[r[f"b{b + 1}_word"] for b in range(n)] for r in rows]
        moved = sum(w != "e" for w in out["words"][-1])
    assert moved > 0  # else the image record compared above is the start's
