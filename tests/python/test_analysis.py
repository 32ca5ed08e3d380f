"""sesi.analysis (docs/observables.md): the numbers of `sesi analyze`, bit for bit (one compiled
library), from a run directory and from arrays; bad input as InputError."""
import csv
import math
import subprocess
import sys

import numpy as np
import pytest

import sesi
import sesi.analysis as sa


def lj_scene(path, bodies=30):
    """A small Lennard-Jones gas on S^2 (bodies on a Fibonacci spiral, tangent velocities)."""
    radius = math.sqrt(bodies / (4 * math.pi * 0.3))
    golden = math.pi * (3 - math.sqrt(5))
    lines = ['name = "analysis-py"', "[space]", 'kind = "sphere"', "dim = 2", f"radius = {radius!r}"]
    for k in range(bodies):
        z = 1 - 2 * (k + 0.5) / bodies
        rho = math.sqrt(1 - z * z)
        x = [radius * rho * math.cos(k * golden), radius * rho * math.sin(k * golden), radius * z]
        t = [-x[1], x[0], 0.0]
        norm = math.hypot(t[0], t[1]) or 1.0
        v = [(0.5 + 0.5 * math.sin(k)) * c / norm for c in t]
        lines += ["[[bodies]]", f"mass = {1.0 + (k % 2)!r}", f"x = {x!r}", f"v = {v!r}"]
    lines += ["[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5",
              "[integrator]", 'method = "sesi2"', "dt = 0.005", "t_end = 1.0", "output_every = 10"]
    path.write_text("\n".join(lines) + "\n")
    return path


def columns(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: np.array([float(r[k]) for r in rows[1:]]) for k, name in enumerate(rows[0])}


def test_the_programs_numbers_bit_for_bit(program, tmp_path):
    scene = lj_scene(tmp_path / "lj.toml")
    out = tmp_path / "out"
    subprocess.run([program, "run", str(scene), "--out", str(out), "-q"], check=True, capture_output=True)
    subprocess.run([program, "analyze", str(out), "--bins", "40", "--from", "0.2", "--max-lag", "7", "--no-picture",
                    "-q"], check=True, capture_output=True)
    g = sa.rdf(out, bins=40, t_from=0.2)
    rdf = columns(out / "rdf.csv")
    np.testing.assert_array_equal(g.r, rdf["r"])
    np.testing.assert_array_equal(g.g, rdf["g"])
    np.testing.assert_array_equal(g.counts, rdf["count"])
    np.testing.assert_array_equal(g.expected, rdf["expected"])
    m = sa.msd(out, max_lag=7, t_from=0.2)
    msd = columns(out / "msd.csv")
    np.testing.assert_array_equal(m.t, msd["t"])
    np.testing.assert_array_equal(m.value, msd["msd"])
    np.testing.assert_array_equal(m.samples, msd["samples"])
    c = sa.vacf(out, max_lag=7, t_from=0.2)
    np.testing.assert_array_equal(c.value, columns(out / "vacf.csv")["vacf"])
    # The frames read back are the trajectory's embedding points; arrays give the same g(r).
    f = sa.read(out, t_from=0.2)
    assert f.space == "sphere" and f.dim == 2 and f.x.shape == (17, 30, 3) and f.v.shape == f.x.shape
    np.testing.assert_array_equal(sa.rdf(f.x, bins=40, space="sphere", radius=f.radius).g, g.g)
    np.testing.assert_array_equal(sa.msd(f.x, max_lag=7, space="sphere", radius=f.radius, t=f.t).value, m.value)
    np.testing.assert_array_equal(sa.vacf(f.x, max_lag=7, v=f.v, space="sphere", radius=f.radius, t=f.t).value,
                                  c.value)


def test_arrays_on_each_space_and_all_pairs():
    rng = np.random.default_rng(5)
    # E^2: a square of bodies; the neighbour cells and all pairs count the same pairs.
    points = rng.uniform(0, 10, size=(3, 300, 2))
    cells = sa.rdf(points, r_max=1.5, bins=15, space="euclidean")
    pairs = sa.rdf(points, r_max=1.5, bins=15, space="euclidean", all_pairs=True)
    np.testing.assert_array_equal(cells.counts, pairs.counts)
    assert cells.frames == 3 and cells.counts.sum() > 0
    # An explicit region on H^2: the disc of radius 2 about the origin.
    r = np.arccosh(1 + rng.uniform(size=400) * (np.cosh(2.0) - 1))
    phi = rng.uniform(0, 2 * np.pi, size=400)
    h = np.stack([np.sinh(r) * np.cos(phi), np.sinh(r) * np.sin(phi), np.cosh(r)], axis=1)
    g = sa.rdf(h, r_max=0.5, bins=5, space="hyperbolic", region=([0, 0, 1], 2.0))
    assert g.centres == int(np.sum(r <= 1.5))
    assert sa.msd_saturation("sphere", 2, 2.0) == pytest.approx(4 * (math.pi ** 2 / 2 - 2), rel=1e-13)
    assert math.isnan(sa.msd_saturation("hyperbolic", 2, 1.0))


def test_bad_input_is_an_input_error(tmp_path):
    with pytest.raises(sesi.InputError, match="no summary.json"):
        sa.rdf(tmp_path)
    with pytest.raises(sesi.InputError, match="space"):
        sa.rdf(np.zeros((4, 3)))
    with pytest.raises(sesi.InputError, match="coordinates per body"):
        sa.rdf(np.zeros((4, 3)), space="euclidean", dim=2)
    with pytest.raises(sesi.InputError, match="rdf-max"):
        sa.rdf(np.eye(3), space="sphere", r_max=4.0)
    with pytest.raises(sesi.InputError, match="velocities"):
        sa.vacf(np.eye(3), space="sphere")


def test_the_example_runs(program, source_dir, tmp_path):
    # examples/python/observables.py, whose lines docs/observables.md shows.
    r = subprocess.run([sys.executable, str(source_dir / "examples" / "python" / "observables.py"), program],
                       cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    counts, msd_last, vacf0, saturation = map(float, r.stdout.split())
    assert counts > 0 and msd_last > 0 and vacf0 > 0
    assert saturation == pytest.approx(math.pi ** 2 / 2 - 2, rel=1e-13)  # the unit sphere's


def test_topology_runs_and_arrays(program, tmp_path):
    # A periodic box and a genus-2 surface (issue #26): a run directory gives its topology, image
    # counts and words, and the numbers of `sesi analyze` bit for bit; arrays with box=/genus= and
    # images=/words= give the same.
    box = tmp_path / "box.toml"
    box.write_text('[space]\nkind = "euclidean"\ndim = 2\nbox = [3.0, 4.0]\n'
                   '[[bodies]]\nmass = 1.0\nq = [0.5, 3.9]\np = [0.7, -0.45]\n'
                   '[[bodies]]\nmass = 2.0\nq = [2.9, 0.1]\np = [-0.4, 2.6]\n'
                   '[integrator]\nmethod = "sesi2"\ndt = 0.05\nt_end = 10.0\noutput_every = 10\n')
    r, phi = 0.3, 0.4
    x = [math.sinh(r) * math.cos(phi), math.sinh(r) * math.sin(phi), math.cosh(r)]
    v = [1.5 * math.cosh(r) * math.cos(phi), 1.5 * math.cosh(r) * math.sin(phi), 1.5 * math.sinh(r)]
    surface = tmp_path / "surface.toml"
    surface.write_text(f'[space]\nkind = "hyperbolic"\ndim = 2\nradius = 1.0\ngenus = 2\n'
                       f'[[bodies]]\nmass = 1.0\nx = {x!r}\nv = {v!r}\n'
                       '[integrator]\nmethod = "sesi2"\ndt = 0.01\nt_end = 6.0\noutput_every = 20\n')
    for scene in (box, surface):
        out = tmp_path / scene.stem
        subprocess.run([program, "run", str(scene), "--out", str(out), "-q"], check=True, capture_output=True)
        subprocess.run([program, "analyze", str(out), "--max-lag", "8", "--no-picture", "-q"], check=True,
                       capture_output=True)
        f = sa.read(out)
        m = sa.msd(out, max_lag=8)
        np.testing.assert_array_equal(m.value, columns(out / "msd.csv")["msd"])
        np.testing.assert_array_equal(sa.rdf(out).g, columns(out / "rdf.csv")["g"])
        if scene is box:
            assert f.box == [3.0, 4.0] and f.genus is None and f.words is None
            assert f.images.shape == (f.x.shape[0], 2, 2) and np.abs(f.images).max() >= 2
            arrays = sa.msd(f.x, max_lag=8, space="euclidean", box=f.box, images=f.images, t=f.t)
            assert sa.max_cutoff("euclidean", 2, box=f.box) == 1.5
        else:
            assert f.genus == 2 and f.box is None and f.images is None
            assert len(f.words) == f.x.shape[0] and any(w[0] != "e" for w in f.words)
            arrays = sa.msd(f.x, max_lag=8, space="hyperbolic", genus=2, words=f.words, t=f.t)
            np.testing.assert_array_equal(sa.vacf(out, max_lag=8).value, columns(out / "vacf.csv")["vacf"])
        np.testing.assert_array_equal(arrays.value, m.value)
    # Beyond the largest cutoff, and a box's MSD without its image counts: InputError.
    with pytest.raises(sesi.InputError, match="largest allowed cutoff is 1.5"):
        sa.rdf(np.array([[0.5, 0.5], [1.0, 1.0]]), r_max=1.6, space="euclidean", box=[3.0, 4.0])
    with pytest.raises(sesi.InputError, match="image counts"):
        sa.msd(np.zeros((2, 1, 2)), space="euclidean", box=[3.0, 4.0])
