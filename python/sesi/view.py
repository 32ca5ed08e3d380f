"""The viewer from Python (docs/view.md, docs/python.md): a run, or a Simulation's rows, as one
self-contained HTML page that shows the bodies moving on S^n, H^n or E^n in a browser.

    import sesi
    v = sesi.view("sesi-out/bulk-lj")      # a run directory, as `sesi view` reads it
    v.save("bulk-lj.html")
    v                                      # in Jupyter: the viewer inline
    out = sim.run(t_end=10.0, output_every=10)
    sim.view(out).save("run.html")         # a Simulation's rows

The page is the program's (`sesi view`'s page writer, one compiled library): sesi.view(dir) gives
the bytes `sesi view DIR --out FILE` writes with the same options.
"""
import html as _html
import numbers
import os
import pathlib
import tempfile

from . import _sesi

__all__ = ["View", "view"]


def _precision(value):
    """"auto", 32 or 64 (also "32", "64") as the command's --precision text."""
    if isinstance(value, str) and value in ("auto", "32", "64"):
        return value
    if isinstance(value, numbers.Integral) and not isinstance(value, bool) and value in (32, 64):
        return str(int(value))
    raise _sesi.InputError(f"precision: expected \"auto\", 32 or 64, got {value!r}")


def _count(name, value):
    """A whole number >= 1 (max_frames, every)."""
    if isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= 1:
        return int(value)
    raise _sesi.InputError(f"{name}: expected a whole number >= 1, got {value!r}")


class View:
    """A viewer page (sesi.view, Simulation.view): .html is the page's text, .save(path) writes it;
    in Jupyter it shows inline (an <iframe> of the page). Also: title, space ("S^2", "H^2", ...),
    bodies, frames, complete and status (why an unfinished run stopped)."""

    def __init__(self, page):
        self.html = page["html"]
        self.title = page["title"]
        self.space = page["space"]
        self.bodies = page["bodies"]
        self.frames = page["frames"]
        self.complete = page["complete"]
        self.status = page["status"]
        self._topology = ("" if page["box"] is None else f" box {page['box']}") + \
            ("" if page["genus"] is None else f" genus {page['genus']}")

    def save(self, path):
        """Write the page to path (atomically: a whole page or nothing); returns the path."""
        path = pathlib.Path(path)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        try:
            with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
                f.write(self.html)
            os.chmod(tmp, 0o644)
            os.replace(tmp, path)
        except BaseException:
            os.unlink(tmp)
            raise
        return path

    def _repr_html_(self):
        # The page in an iframe (its own document: its script and style stay inside), scripts allowed.
        return (f'<iframe srcdoc="{_html.escape(self.html, quote=True)}" width="100%" height="640" '
                f'sandbox="allow-scripts" style="border: 0"></iframe>')

    def __repr__(self):
        state = "" if self.complete else ", not complete"
        return f"<sesi.View {self.title!r}: {self.space}{self._topology}, {self.bodies} bodies, {self.frames} frames{state}>"


def view(run_dir, *, t_from=None, t_to=None, every=1, max_frames=1000, precision="auto"):
    """The viewer page of a run directory, as `sesi view DIR` writes it: the frames with t in
    [t_from, t_to], every k-th of them, thinned evenly to at most max_frames (the first and last
    kept); positions as float32 ("auto": float64 where float32 cannot place the bodies, far out on
    H^n), or precision=32 / 64. An unfinished run gives a page with its banner (View.complete
    False). Raises InputError (the program's message) for a missing or unreadable run."""
    page = _sesi.view_run(os.fspath(run_dir), None if t_from is None else float(t_from),
                          None if t_to is None else float(t_to), _count("every", every),
                          _count("max_frames", max_frames), _precision(precision))
    return View(page)


def _simulation_view(sim, rows, max_frames, precision, title, status):
    """Simulation.view's page: rows of Simulation.run (or the state as one row)."""
    import numpy

    core = sim._start()
    precision = _precision(precision)
    max_frames = _count("max_frames", max_frames)
    if rows is None:
        # The current state, one frame.
        images = core.image_counts
        words = core.words
        rows = {"t": numpy.array([core.t]), "x": core.x[numpy.newaxis], "v": core.v[numpy.newaxis],
                "energy": numpy.array([core.energy()]),
                "image_counts": None if images is None else numpy.asarray(images)[numpy.newaxis],
                "words": None if words is None else [list(words)]}
        status = ""
    elif not isinstance(rows, dict) or any(key not in rows for key in ("t", "x", "v", "energy")):
        raise _sesi.InputError("rows: expected the dict Simulation.run returned (t, x, v, energy, ...)")
    if title is None:
        title = core.name if core.name and not core.name.startswith("<") else "simulation"  # not "<simulation>"
    page = _sesi.view_rows(core, numpy.asarray(rows["t"], dtype=float).tolist(), rows["x"], rows["v"],
                           numpy.asarray(rows["energy"], dtype=float).tolist(), rows.get("image_counts"),
                           rows.get("words"), str(title), max_frames, precision, status)
    return View(page)


View.__module__ = "sesi"
view.__module__ = "sesi"
