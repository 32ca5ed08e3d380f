"""Observables with the space's own geometry (docs/observables.md), as NumPy arrays.

    import sesi.analysis as sa
    g = sa.rdf("sesi-out/lj")                 # a finished run's directory, as `sesi analyze` reads it
    print(g.r, g.g)
    m = sa.msd("sesi-out/lj", max_lag=100)    # mean-squared geodesic displacement
    c = sa.vacf("sesi-out/lj")                # velocity autocorrelation (parallel transport)
    g = sa.rdf(points, space="sphere", radius=3.0, r_max=2.0)   # frames of embedding points

The numbers are those of `sesi analyze` (one compiled library, src/analysis): g(r) in geodesic
distance normalised by the exact shell measure of S^n, H^n or E^n; on H^n and E^n over the
bodies' region (a geodesic ball; by default the one about their centre that holds them all), with
only the bodies at least r_max inside it as shell centres.
"""
import collections
import os

import numpy

from . import _sesi

__all__ = ["Frames", "RDF", "Correlation", "read", "rdf", "msd", "vacf", "msd_saturation"]

Frames = collections.namedtuple("Frames", "space dim radius t x v masses")
Frames.__doc__ = """A run's frames: space ("sphere", "hyperbolic", "euclidean"), dim, radius, t (F,),
x (F, N, A) embedding points, v (F, N, A) embedding velocities or None (masses unknown), masses."""

RDF = collections.namedtuple("RDF", "r g edges counts expected frames centres")
RDF.__doc__ = """g(r): bin centres r, g, the bin edges, the ordered pair counts (centre, other), the
counts an ideal gas would give, the frames and the shell centres counted over them."""

Correlation = collections.namedtuple("Correlation", "t value samples per_body")
Correlation.__doc__ = """A time correlation: lag times t, its value at each lag (mean over time origins
and bodies), the samples averaged, and per body the mean at the longest lag."""


def _is_path(source):
    return isinstance(source, (str, os.PathLike))


def read(run_dir, t_from=None, t_to=None, every=1):
    """The frames of a finished run's trajectory (trajectory.csv or trajectory.h5) with t in
    [t_from, t_to], every k-th of them, as `sesi analyze` reads them."""
    d = _sesi.analysis_read(os.fspath(run_dir), t_from, t_to, int(every))
    return Frames(d["space"], d["dim"], d["radius"], d["t"], d["x"], d["v"], list(d["masses"]))


def _frames(source, space, dim, radius, t, t_from, t_to, every):
    """(space, dim, radius, t, x, v) from a run directory or from arrays of embedding points."""
    if _is_path(source):
        f = read(source, t_from, t_to, every)
        return f.space, f.dim, f.radius, f.t, f.x, f.v
    if space is None:
        raise _sesi.InputError("space: give the space of the points (\"sphere\", \"hyperbolic\" or \"euclidean\")")
    x = numpy.asarray(source, dtype=float)
    if x.ndim == 2:
        x = x[numpy.newaxis]
    if x.ndim != 3:
        raise _sesi.InputError("points: expected an array (bodies, coordinates) or (frames, bodies, coordinates)")
    if dim is None:
        dim = x.shape[2] if space == "euclidean" else x.shape[2] - 1
    if t is None:
        t = numpy.arange(x.shape[0], dtype=float)
    return space, int(dim), float(radius), numpy.asarray(t, dtype=float), x, None


def rdf(source, r_max=None, bins=100, *, space=None, dim=None, radius=1.0, region=None, t_from=None, t_to=None,
        every=1, all_pairs=False):
    """g(r) of a run directory's frames, or of embedding points (bodies, A) or (frames, bodies, A)
    on the space given by space, dim (default: from A) and radius.

    r_max: largest distance (default as `sesi analyze`: pi R on S^n, elsewhere a quarter of the first
    frame's extent, at most ten mean spacings);
    region: (center, radius) of the ball over which the density is taken on H^n and E^n;
    all_pairs: count all pairs instead of the neighbour cells (the same counts; for tests)."""
    space, dim, radius, _, x, _ = _frames(source, space, dim, radius, None, t_from, t_to, every)
    center, region_radius = (None, None) if region is None else (numpy.asarray(region[0], dtype=float), float(region[1]))
    d = _sesi.analysis_rdf(space, dim, radius, x, r_max, int(bins), center, region_radius, bool(all_pairs))
    return RDF(d["r"], d["g"], d["edges"], d["counts"], d["expected"], d["frames"], d["centres"])


def msd(source, max_lag=None, *, space=None, dim=None, radius=1.0, t=None, t_from=None, t_to=None, every=1):
    """Mean-squared geodesic displacement over time origins and bodies at lags 0..max_lag frames
    (default: half the frames), of a run directory or of frames of embedding points (with times t)."""
    space, dim, radius, t, x, _ = _frames(source, space, dim, radius, t, t_from, t_to, every)
    d = _sesi.analysis_msd(space, dim, radius, t, x, -1 if max_lag is None else int(max_lag))
    return Correlation(d["t"], d["value"], d["samples"], d["per_body"])


def vacf(source, max_lag=None, *, v=None, space=None, dim=None, radius=1.0, t=None, t_from=None, t_to=None,
         every=1):
    """Velocity autocorrelation <P v(t0), v(t0 + t)> (v(t0) carried to v(t0 + t)'s point by parallel
    transport along the geodesic) of a run directory, or of frames of embedding points with
    embedding velocities v."""
    space, dim, radius, t, x, run_v = _frames(source, space, dim, radius, t, t_from, t_to, every)
    if _is_path(source):
        v = run_v
    if v is None:
        raise _sesi.InputError("vacf: needs the velocities (a run's masses in summary.json, or v=)")
    d = _sesi.analysis_vacf(space, dim, radius, t, x, numpy.asarray(v, dtype=float),
                            -1 if max_lag is None else int(max_lag))
    return Correlation(d["t"], d["value"], d["samples"], d["per_body"])


def msd_saturation(space, dim, radius=1.0):
    """S^n: the mean squared geodesic distance of two independent uniform points, where the MSD
    saturates (R^2 (pi^2/2 - 2) on S^2); NaN on H^n and E^n."""
    return _sesi.analysis_msd_saturation(space, int(dim), float(radius))
