"""Observables with the space's own geometry (docs/observables.md), as NumPy arrays.

    import sesi.analysis as sa
    g = sa.rdf("sesi-out/lj")                 # a finished run's directory, as `sesi analyze` reads it
    print(g.r, g.g)
    m = sa.msd("sesi-out/lj", max_lag=100)    # mean-squared geodesic displacement
    c = sa.vacf("sesi-out/lj")                # velocity autocorrelation (parallel transport)
    g = sa.rdf(points, space="sphere", radius=3.0, r_max=2.0)   # frames of embedding points
    g = sa.rdf(points, space="euclidean", box=[10.0, 10.0])      # a periodic box (minimum image)

The numbers are those of `sesi analyze` (one compiled library, src/analysis): g(r) in geodesic
distance normalised by the exact shell measure of S^n, H^n or E^n; on H^n and E^n over the
bodies' region (a geodesic ball; by default the one about their centre that holds them all), with
only the bodies at least r_max inside it as shell centres. On a periodic box (E^n, box=[L1, ..., Ln])
or a compact surface (H^2, genus=g) every distance is the minimum-image one, g(r) reaches at most the
topology's largest cutoff over the domain's volume, and the MSD follows the unwrapped positions: the
image counts (images=) or the words (words=), which a run directory provides.
"""
import collections
import os

import numpy

from . import _sesi

__all__ = ["Frames", "RDF", "Correlation", "read", "rdf", "msd", "vacf", "msd_saturation", "max_cutoff"]

Frames = collections.namedtuple("Frames", "space dim radius t x v masses box genus images words")
Frames.__doc__ = """A run's frames: space ("sphere", "hyperbolic", "euclidean"), dim, radius, t (F,),
x (F, N, A) embedding points (in the domain on a topology), v (F, N, A) embedding velocities or None
(masses unknown), masses; box (the edges of a periodic box, or None), genus (of a compact surface, or
None), images (F, N, dim) int64 image counts on a box (unwrapped x + L n) or None, words (F lists of N
str: "e" or 1-based side numbers joined by '.') on a surface or None."""

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
    return Frames(d["space"], d["dim"], d["radius"], d["t"], d["x"], d["v"], list(d["masses"]), d["box"], d["genus"],
                  d["images"], d["words"])


def _frames(source, space, dim, radius, t, t_from, t_to, every):
    """A Frames from a run directory or from arrays of embedding points (box, genus, images and
    words None: the callers add theirs)."""
    if _is_path(source):
        return read(source, t_from, t_to, every)
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
    return Frames(space, int(dim), float(radius), numpy.asarray(t, dtype=float), x, None, [], None, None, None, None)


def _topology(f, box, genus, images, words):
    """(box, genus, images, words): a run's own, or those given with arrays."""
    if f.box is not None or f.genus is not None:
        return f.box, f.genus, f.images, f.words
    box = None if box is None else [float(edge) for edge in box]
    genus = None if genus is None else int(genus)
    images = None if images is None else numpy.asarray(images, dtype=numpy.int64)
    if images is not None and images.ndim == 2:
        images = images[numpy.newaxis]
    if words is not None and len(words) > 0 and isinstance(words[0], str):
        words = [list(words)]
    return box, genus, images, None if words is None else [list(row) for row in words]


def rdf(source, r_max=None, bins=100, *, space=None, dim=None, radius=1.0, box=None, genus=None, region=None,
        t_from=None, t_to=None, every=1, all_pairs=False):
    """g(r) of a run directory's frames, or of embedding points (bodies, A) or (frames, bodies, A)
    on the space given by space, dim (default: from A), radius and its topology (box=[L1, ..., Ln] on
    E^n, genus=g on H^2; a run directory gives its own).

    r_max: largest distance (default as `sesi analyze`: pi R on S^n, the largest allowed cutoff on a
    box or surface, elsewhere a quarter of the first frame's extent; at most ten mean spacings);
    region: (center, radius) of the ball over which the density is taken on H^n and E^n without a topology;
    all_pairs: count all pairs instead of the neighbour cells (the same counts; for tests)."""
    f = _frames(source, space, dim, radius, None, t_from, t_to, every)
    box, genus, _, _ = _topology(f, box, genus, None, None)
    center, region_radius = (None, None) if region is None else (numpy.asarray(region[0], dtype=float), float(region[1]))
    d = _sesi.analysis_rdf(f.space, f.dim, f.radius, f.x, r_max, int(bins), center, region_radius, bool(all_pairs),
                           box, genus)
    return RDF(d["r"], d["g"], d["edges"], d["counts"], d["expected"], d["frames"], d["centres"])


def msd(source, max_lag=None, *, space=None, dim=None, radius=1.0, box=None, genus=None, images=None, words=None,
        t=None, t_from=None, t_to=None, every=1):
    """Mean-squared geodesic displacement over time origins and bodies at lags 0..max_lag frames
    (default: half the frames), of a run directory or of frames of embedding points (with times t).
    On a box or surface, of the unwrapped positions: images (frames, bodies, dim) image counts with
    box=, or words (frames lists of bodies words) with genus=; a run directory gives its own."""
    f = _frames(source, space, dim, radius, t, t_from, t_to, every)
    box, genus, images, words = _topology(f, box, genus, images, words)
    d = _sesi.analysis_msd(f.space, f.dim, f.radius, f.t, f.x, -1 if max_lag is None else int(max_lag), box, genus,
                           images, words)
    return Correlation(d["t"], d["value"], d["samples"], d["per_body"])


def vacf(source, max_lag=None, *, v=None, space=None, dim=None, radius=1.0, box=None, genus=None, words=None, t=None,
         t_from=None, t_to=None, every=1):
    """Velocity autocorrelation <P v(t0), v(t0 + t)> (v(t0) carried to v(t0 + t)'s point by parallel
    transport along the geodesic) of a run directory, or of frames of embedding points with
    embedding velocities v (on a surface, with the words: the isometry between the tiles first)."""
    f = _frames(source, space, dim, radius, t, t_from, t_to, every)
    box, genus, _, words = _topology(f, box, genus, None, words)
    if _is_path(source):
        v = f.v
    if v is None:
        raise _sesi.InputError("vacf: needs the velocities (a run's masses in summary.json, or v=)")
    d = _sesi.analysis_vacf(f.space, f.dim, f.radius, f.t, f.x, numpy.asarray(v, dtype=float),
                            -1 if max_lag is None else int(max_lag), box, genus, None, words)
    return Correlation(d["t"], d["value"], d["samples"], d["per_body"])


def msd_saturation(space, dim, radius=1.0):
    """S^n: the mean squared geodesic distance of two independent uniform points, where the MSD
    saturates (R^2 (pi^2/2 - 2) on S^2); NaN on H^n and E^n."""
    return _sesi.analysis_msd_saturation(space, int(dim), float(radius))


def max_cutoff(space, dim, radius=1.0, *, box=None, genus=None):
    """The largest r of g(r) on a periodic box (E^n, box=[...]) or compact surface (H^2, genus=g):
    the topology's largest allowed cutoff; inf without a topology."""
    return _sesi.analysis_max_cutoff(space, int(dim), float(radius),
                                     None if box is None else [float(e) for e in box],
                                     None if genus is None else int(genus))
