"""sesi.view and Simulation.view (docs/python.md, docs/view.md): the page of `sesi view`, byte for
byte (one page writer), from a run directory and from a Simulation's rows; the frames decode to the
rows' points; a box's jumps, a surface's polygon; the Jupyter iframe; bad input as InputError."""
import base64
import html
import importlib
import json
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

import sesi


def meta_and_frames(page):
    """The page's meta JSON and its frame lines, each split into its base64 parts."""
    meta = re.search(r'<script type="application/json" id="sesi-meta">(.*?)</script>', page, re.S).group(1)
    text = re.search(r'<script type="text/plain" id="sesi-frames">(.*?)</script>', page, re.S).group(1)
    return json.loads(meta), [line.split(",") for line in text.strip("\n").split("\n")]


def positions(meta, line):
    """A frame line's positions as (bodies, ambient) float64."""
    dtype = "<f4" if meta["frames"]["encoding"] == "f32" else "<f8"
    x = np.frombuffer(base64.b64decode(line[0], validate=True), dtype=dtype)
    return x.astype(float).reshape(meta["bodies"], meta["ambient"])


def extras(meta, line):
    """A frame line's speeds (float32) and jump flags (uint8), each None when the page has none."""
    parts = line[1:]
    speed = np.frombuffer(base64.b64decode(parts.pop(0)), dtype="<f4") if meta["frames"]["speed"] else None
    jumps = np.frombuffer(base64.b64decode(parts.pop(0)), dtype=np.uint8) if meta["frames"]["jumps"] else None
    assert not parts
    return speed, jumps


# float32 rounding to nearest: |fl(x) - x| <= 2^-24 |x| per number.
F32 = 2.0 ** -24

SCENE = """name = "view-py"
[space]
kind = "sphere"
dim = 2
radius = 2.0
[[bodies]]
mass = 1.0
x = [2.0, 0.0, 0.0]
v = [0.0, 0.4, 0.1]
[[bodies]]
mass = 0.5
x = [0.0, 2.0, 0.0]
v = [-0.3, 0.0, 0.2]
[[bodies]]
mass = 2.0
x = [0.0, 1.2, 1.6]
v = [0.1, -0.2, 0.15]
[[potential]]
kind = "cotangent-gravity"
G = 0.2
[integrator]
method = "sesi4"
dt = 0.01
t_end = 2.0
output_every = 5
"""


@pytest.fixture(scope="module")
def run_dir(program, tmp_path_factory):
    """A finished run of three bodies on S^2 (41 frames)."""
    tmp = tmp_path_factory.mktemp("view")
    (tmp / "scene.toml").write_text(SCENE)
    out = tmp / "run"
    subprocess.run([program, "run", str(tmp / "scene.toml"), "--out", str(out), "-q"], check=True,
                   capture_output=True)
    return out


def hyperbolic_bodies(radius=1.0):
    """Three bodies near the origin of H^2 of radius R, with tangent velocities (<x, v>_L = 0)."""
    rows_x, rows_v = [], []
    for k, (d, phi, speed) in enumerate([(0.2, 0.0, 0.5), (0.5, 2.0, 0.3), (0.8, 4.0, 0.7)]):
        x = [radius * math.sinh(d) * math.cos(phi), radius * math.sinh(d) * math.sin(phi), radius * math.cosh(d)]
        # The unit tangent of the radial geodesic, turned by k: the velocity's direction.
        radial = np.array([math.cosh(d) * math.cos(phi), math.cosh(d) * math.sin(phi), math.sinh(d)])
        around = np.array([-math.sin(phi), math.cos(phi), 0.0])
        rows_x.append(x)
        rows_v.append(list(speed * (math.cos(k) * radial + math.sin(k) * around)))
    return np.array(rows_x), np.array(rows_v)


def test_same_bytes_as_the_program(program, run_dir, tmp_path):
    # One page writer: sesi.view(dir, ...) is what `sesi view DIR --out FILE ...` writes, byte for byte.
    for options, arguments in [({}, []),
                               (dict(t_from=0.3, t_to=1.7, every=2, max_frames=5, precision=64),
                                ["--from", "0.3", "--to", "1.7", "--every", "2", "--max-frames", "5",
                                 "--precision", "64"])]:
        page = tmp_path / f"page{len(arguments)}.html"
        subprocess.run([program, "view", str(run_dir), "--out", str(page), "--quiet", *arguments], check=True,
                       capture_output=True)
        v = sesi.view(run_dir, **options)
        assert v.html.encode("utf-8") == page.read_bytes()
    meta, lines = meta_and_frames(v.html)
    assert meta["format"] == "sesi-view 1" and meta["title"] == "run"
    assert meta["frames"]["count"] == 5 == len(lines) == v.frames and meta["frames"]["encoding"] == "f64"
    assert v.space == "S^2" and v.bodies == 3 and v.complete
    assert repr(v) == "<sesi.View 'run': S^2, 3 bodies, 5 frames>"


def test_simulation_rows(tmp_path):
    x, vel = hyperbolic_bodies()
    sim = sesi.Simulation(space="hyperbolic", dim=2, radius=1.0, name="three")
    sim.add_bodies([1.0, 2.0, 0.5], x=x, v=vel)
    sim.add_potential("lennard-jones", epsilon=1.0, sigma=0.4, cutoff=1.0)
    sim.dt = 0.01
    out = sim.run(t_end=1.0, output_every=10)
    v = sim.view(out, title="three bodies")
    meta, lines = meta_and_frames(v.html)
    rows = len(out["t"])
    assert meta["space"]["kind"] == "hyperbolic" and meta["space"]["dim"] == 2 and meta["space"]["radius"] == 1.0
    assert meta["title"] == "three bodies" and meta["ambient"] == 3 and meta["bodies"] == 3
    assert meta["masses"] == [1.0, 2.0, 0.5] and meta["body_radius"] == 0.2  # half the smallest sigma
    assert meta["complete"] is True and meta["frames"]["count"] == rows == len(lines)
    assert meta["frames"]["t"] == out["t"].tolist()  # %.17g: the doubles read back exactly
    assert meta["frames"]["encoding"] == "f32" and meta["frames"]["speed"] and not meta["frames"]["jumps"]
    for k in (0, rows - 1):
        got = positions(meta, lines[k])
        assert np.all(np.abs(got - out["x"][k]) <= F32 * np.abs(out["x"][k]))
        speed, _ = extras(meta, lines[k])
        w = out["v"][k]
        exact = np.sqrt(w[:, 0] ** 2 + w[:, 1] ** 2 - w[:, 2] ** 2)  # the Minkowski norm of a tangent vector
        # float32 rounding, plus the double sums' rounding (a few 2^-53 relative, times cosh^2(0.8) < 2
        # from the cancellation between the space-like and time-like parts).
        assert np.all(np.abs(speed - exact) <= (F32 + 2.0 ** -48) * exact)
    # The diagnostics: the energy error relative to the first row, and 2K / (N n).
    series = {s["name"]: s for s in meta["diagnostics"]["series"]}
    error = series["relative energy error"]
    assert error["t"] == out["t"].tolist()
    assert error["y"] == ((out["energy"] - out["energy"][0]) / abs(out["energy"][0])).tolist()
    w = out["v"]
    twice_kinetic = (np.array([1.0, 2.0, 0.5]) * (w[:, :, 0] ** 2 + w[:, :, 1] ** 2 - w[:, :, 2] ** 2)).sum(axis=1)
    # Another order of a few roundings (2^-53 each), times the cancellation's factor (< 2 cosh^2(1.8) < 20).
    np.testing.assert_allclose(series["kinetic temperature"]["y"], twice_kinetic / (3 * 2), rtol=2.0 ** -45, atol=0)
    # Thinned to 4 frames: the first and the last kept.
    meta4, lines4 = meta_and_frames(sim.view(out, max_frames=4).html)
    assert meta4["frames"]["count"] == 4 == len(lines4) and meta4["frames"]["thinned_from"] == rows
    assert meta4["frames"]["t"][0] == out["t"][0] and meta4["frames"]["t"][-1] == out["t"][-1]
    # precision 64: the rows' points bit for bit.
    meta64, lines64 = meta_and_frames(sim.view(out, precision=64).html)
    assert meta64["frames"]["encoding"] == "f64"
    np.testing.assert_array_equal(positions(meta64, lines64[-1]), out["x"][-1])
    # No rows given: the last run's; before any run, the state as one frame.
    assert sim.view(title="three bodies").html == v.html
    assert meta_and_frames(sim.view().html)[0]["title"] == "three"  # the scene's name
    fresh = sesi.Simulation(space="hyperbolic", dim=2)
    fresh.add_bodies(1.0, x=x, v=vel)
    one = fresh.view()
    meta1, lines1 = meta_and_frames(one.html)
    assert meta1["frames"]["count"] == 1 == one.frames and meta1["frames"]["t"] == [0.0]
    assert np.all(np.abs(positions(meta1, lines1[0]) - x) <= F32 * np.abs(x))
    assert meta1["body_radius"] == 0  # no Lennard-Jones term: unknown


def test_far_bodies_take_float64():
    # "auto": a body 6 R out on H^2 (beyond 5 R, where float32 keeps too few digits of x_last ~ R e^6 / 2)
    # puts float64 positions in the page, the points bit for bit; precision=32 keeps float32.
    x = np.array([[math.sinh(6.0), 0.0, math.cosh(6.0)], [0.0, math.sinh(0.3), math.cosh(0.3)]])
    sim = sesi.Simulation(space="hyperbolic", dim=2)
    sim.add_bodies(1.0, x=x, v=np.zeros_like(x))
    meta, lines = meta_and_frames(sim.view().html)
    assert meta["frames"]["encoding"] == "f64"
    np.testing.assert_array_equal(positions(meta, lines[0]), sim.x)
    assert meta_and_frames(sim.view(precision=32).html)[0]["frames"]["encoding"] == "f32"


def test_box_jumps():
    # Two bodies crossing the faces of a 3 x 4 box: a body's jump flag is 1 exactly where its image
    # counts changed since the previous frame.
    sim = sesi.Simulation(space="euclidean", dim=2, box=[3.0, 4.0])
    sim.add_body(mass=1.0, q=[0.5, 3.9], p=[0.7, -0.45])
    sim.add_body(mass=2.0, q=[2.9, 0.1], p=[-0.4, 2.6])
    sim.method, sim.dt = "sesi2", 0.05
    out = sim.run(t_end=10.0, output_every=10)
    v = sim.view()
    meta, lines = meta_and_frames(v.html)
    assert meta["space"]["box"] == [3.0, 4.0] and meta["frames"]["jumps"] and meta["polygon"] is None
    counts = out["image_counts"]
    changed = np.concatenate([np.zeros((1, 2), bool), (counts[1:] != counts[:-1]).any(axis=2)])
    jumps = np.array([extras(meta, line)[1] for line in lines])
    np.testing.assert_array_equal(jumps, changed.astype(np.uint8))
    assert jumps.sum() >= 2  # both bodies crossed a face (else the check above holds for no jumps at all)
    assert repr(v) == "<sesi.View 'simulation': E^2 box [3.0, 4.0], 2 bodies, 21 frames>"


def test_surface_polygon():
    # The genus-2 (Bolza) surface of radius R: the regular octagon with angles pi/4, whose vertices lie at
    # cosh(d / R) = cot^2(pi / 8) = 3 + 2 sqrt 2 from the centre (a regular N-gon of angle alpha has
    # cosh(circumradius) = cot(pi / N) cot(alpha / 2); Beardon, The Geometry of Discrete Groups, 7.17).
    radius = 2.0
    x, vel = hyperbolic_bodies(radius)
    sim = sesi.Simulation(space="hyperbolic", dim=2, radius=radius, genus=2)
    sim.add_bodies(1.0, x=x, v=vel)
    sim.dt = 0.01
    sim.run(t_end=0.5, output_every=10)
    meta, lines = meta_and_frames(sim.view().html)
    assert meta["space"]["genus"] == 2 and meta["frames"]["jumps"]
    vertices = np.array(meta["polygon"]["vertices"])
    assert vertices.shape == (8, 3)
    lorentz = vertices[:, 0] ** 2 + vertices[:, 1] ** 2 - vertices[:, 2] ** 2
    # A few roundings of numbers of size R cosh(d / R) ~ 12: 1e-12 relative to R^2 holds them.
    assert np.all(np.abs(lorentz + radius ** 2) <= 1e-12 * radius ** 2)
    assert np.all(np.abs(vertices[:, 2] - radius * (3 + 2 * math.sqrt(2))) <= 1e-12 * radius * 6)
    tiles = meta["polygon"]["tiles"]
    assert len(tiles) == 1 + 8 * 6 and tiles[0] == [1, 0, 0, 0, 1, 0, 0, 0, 1]  # identity, then 4g(4g-2)


def test_repr_html_and_save(tmp_path):
    x, vel = hyperbolic_bodies()
    sim = sesi.Simulation(space="hyperbolic", dim=2)
    sim.add_bodies(1.0, x=x, v=vel)
    v = sim.view()
    frame = v._repr_html_()
    assert frame.startswith("<iframe ") and frame.endswith("</iframe>")
    assert 'width="100%"' in frame and 'height="640"' in frame and 'sandbox="allow-scripts"' in frame
    srcdoc = re.fullmatch(r'<iframe srcdoc="([^"]*)".*', frame, re.S).group(1)
    assert "<" not in srcdoc and html.unescape(srcdoc) == v.html
    path = v.save(tmp_path / "view.html")
    assert path == tmp_path / "view.html" and path.read_bytes() == v.html.encode("utf-8")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["view.html"]  # no temporary file left


def test_unfinished_run_has_its_banner():
    # An energy guard that trips: the rows up to the last good state, marked not complete.
    sim = sesi.Simulation(space="sphere", dim=2)
    sim.add_body(mass=1.0, x=[1, 0, 0], v=[0, 0.5, 0])
    sim.add_body(mass=1.0, x=[0, 1, 0], v=[-0.5, 0, 0.2])
    sim.add_potential("cotangent-gravity", G=1.0)
    sim.method, sim.dt, sim.energy_guard = "sesi2", 0.2, 1e-2  # trips at step 3
    with pytest.raises(sesi.InstabilityError) as failure:
        sim.run(t_end=10.0, output_every=1)
    v = sim.view()
    meta, lines = meta_and_frames(v.html)
    assert not v.complete and meta["complete"] is False and meta["status"] == str(failure.value)
    assert meta["frames"]["count"] == len(failure.value.output["t"]) == len(lines) == 3
    assert "not complete" in repr(v)


def test_unfinished_run_directory(program, tmp_path):
    # A run stopped by its energy guard: its page (the program's bytes) says so; a directory whose
    # trajectory is missing cannot be read: InputError with the program's message.
    (tmp_path / "scene.toml").write_text(SCENE.replace("dt = 0.01", "dt = 0.3\nenergy_guard = 1e-9"))
    out = tmp_path / "stopped"
    r = subprocess.run([program, "run", str(tmp_path / "scene.toml"), "--out", str(out), "-q"], capture_output=True)
    assert r.returncode != 0 and (out / "trajectory.csv").exists()
    subprocess.run([program, "view", str(out), "--out", str(tmp_path / "page.html"), "--quiet"], check=True,
                   capture_output=True)
    v = sesi.view(out)
    assert v.html.encode("utf-8") == (tmp_path / "page.html").read_bytes()
    assert not v.complete and "energy error exceeded" in v.status and "not complete" in repr(v)
    (out / "trajectory.csv").unlink()
    r = subprocess.run([program, "view", str(out), "--quiet"], capture_output=True, text=True)
    with pytest.raises(sesi.InputError) as e:
        sesi.view(out)
    assert r.returncode == 2 and r.stderr == f"sesi: error: {e.value}\n" and "trajectory" in str(e.value)


def test_errors(program, run_dir, tmp_path):
    # The program's one-line message, as an InputError.
    for missing in (tmp_path / "missing", tmp_path):
        r = subprocess.run([program, "view", str(missing), "--quiet"], capture_output=True, text=True)
        assert r.returncode == 2
        with pytest.raises(sesi.InputError) as e:
            sesi.view(missing)
        assert r.stderr == f"sesi: error: {e.value}\n"
    assert list(tmp_path.iterdir()) == []  # nothing written
    for bad in dict(precision=16), dict(precision="f32"), dict(precision=True), dict(max_frames=0), \
            dict(max_frames=2.5), dict(every=0):
        with pytest.raises(sesi.InputError, match=next(iter(bad))):
            sesi.view(run_dir, **bad)
    sim = sesi.Simulation(space="sphere", dim=2)
    sim.add_body(mass=1.0, x=[1, 0, 0], v=[0, 0.5, 0])
    with pytest.raises(sesi.InputError, match="max_frames"):
        sim.view(max_frames=-1)
    with pytest.raises(sesi.InputError, match="rows"):
        sim.view({"t": [0.0]})
    with pytest.raises(sesi.InputError, match="x: expected an array"):
        sim.view({"t": [0.0], "x": np.zeros((1, 2, 3)), "v": np.zeros((1, 2, 3)), "energy": [0.0]})
    # The function keeps its name beside the submodule's.
    assert importlib.import_module("sesi.view").view is sesi.view and sesi.View.__module__ == "sesi"


def test_example_runs(source_dir, tmp_path):
    # examples/python/view.py, whose lines docs/python.md shows.
    r = subprocess.run([sys.executable, str(source_dir / "examples" / "python" / "view.py")], cwd=tmp_path,
                       capture_output=True, text=True, timeout=60, env={**os.environ, "TMPDIR": str(tmp_path)})
    assert r.returncode == 0, r.stderr
    path = re.search(r"wrote (\S+)", r.stdout).group(1)
    assert path.startswith(str(tmp_path))  # into a temporary directory
    with open(path, encoding="utf-8") as f:
        meta, lines = meta_and_frames(f.read())
    assert meta["space"]["kind"] == "hyperbolic" and meta["frames"]["count"] == len(lines) > 1
    text = (source_dir / "docs" / "python.md").read_text()
    block = text.split("## The viewer", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    assert block in (source_dir / "examples" / "python" / "view.py").read_text()
