"""sesi: explicit, time-reversible, symplectic integration on spheres, hyperbolic spaces and flat
space, from Python (docs/python.md).

    import sesi
    sim = sesi.Simulation(space="sphere", dim=2, radius=1.0)
    sim.add_body(mass=1.0, x=[1, 0, 0], v=[0, 0.3, 0])
    sim.add_body(mass=1.0, x=[0, 1, 0], v=[-0.3, 0, 0])
    sim.add_potential("cotangent-gravity", G=1.0)
    sim.method = "sesi4"; sim.dt = 0.01
    sim.integrate(10.0)
    print(sim.t, sim.x, sim.energy())

The scene, its checks and messages, the methods and the step loop are those of `sesi run`
(one compiled library): a Simulation is a scene file's document built in Python, and a run of it
takes the same steps, bit for bit, as `sesi run` on that file.
"""
import copy

from ._sesi import Core as _Core
from ._sesi import InputError
from ._sesi import methods as _methods
from ._sesi import paper_exact as _paper_exact
from ._sesi import potentials as _potentials
from ._sesi import thermostat_keys as _thermostat_keys
from ._sesi import thermostat_kinds as _thermostat_kinds
from . import analysis  # g(r), MSD, VACF as NumPy arrays (docs/observables.md)
from .view import View, view  # the viewer page (docs/view.md); the function shadows the submodule's name
from .view import _simulation_view

__all__ = ["Simulation", "Thermostat", "InputError", "InstabilityError", "View", "methods", "potentials",
           "thermostats", "paper_exact", "view"]

InputError.__doc__ = """Bad input: a scene key, a value, a setting. A ValueError whose message is the
one line `sesi run` prints for the same mistake (with the key path, e.g. bodies[2].x)."""


class InstabilityError(RuntimeError):
    """A run stopped on a failed check: a non-finite state, the energy guard or a close encounter.

    The message names what failed, the bodies, the step and the time. The simulation is left at
    its last state known good (the last checked step). Attributes: reason, detail, step, t, body
    (1-based, 0 when not known), and output: for Simulation.run, the rows up to the last good
    state (the run's output, incomplete).
    """

    def __init__(self, message, reason="", detail="", step=0, t=0.0, body=0, output=None):
        super().__init__(message)
        self.reason = reason
        self.detail = detail
        self.step = step
        self.t = t
        self.body = body
        self.output = output


def methods():
    """The methods of `sesi run --method`, as `sesi run --list-methods --json` lists them: a list of
    dicts with name, order, family ("chart", "processed", "geodesic" or "reference"), processed,
    stages (force evaluations per step), output_stages (more per state read), spaces (the [space]
    kinds it runs on) and about (the coefficients' source)."""
    return _methods()


def potentials():
    """The potential kinds of the scene format: a list of dicts with kind, keys, defaults and
    energy (docs/scene-format.md)."""
    return _potentials()


def thermostats():
    """The thermostat kinds of the scene format's [thermostat] table (sesi.Thermostat): a list of dicts
    with kind and keys (besides kind and temperature, which every kind takes)."""
    return [{"kind": kind, "keys": [k for k in keys if k != "temperature"]} for kind, keys in _thermostat_kinds()]


def paper_exact(t):
    """The exact embedding points of the seed scene's three bodies at the times t (a number or a
    sequence): an array of shape (len(t), 3, 3) (include/sesi/scenes/paper.hpp,
    ../shared/paper-scene.md). Simulation.paper() is that scene."""
    import numpy

    times = numpy.atleast_1d(numpy.asarray(t, dtype=float))
    return _paper_exact(times.tolist())


class Thermostat:
    """A thermostat: the keys of a scene file's [thermostat] table (docs/scene-format.md).

        sim.thermostat = sesi.Thermostat("langevin", temperature=1.0, gamma=1.0, seed=3)
        sim.thermostat = sesi.Thermostat("nose-hoover", temperature=[(0, 2.0), (50, 0.5)], tau=0.5)
        sim.thermostat = None   # constant energy again

    kind is "langevin" (gamma, seed), "nose-hoover" (tau, chain), "csvr" (tau, seed) or
    "brownian" (gamma, seed); temperature is kT (k_B = 1) or a schedule of (t, kT) knots, linear
    between them. Keys left out take the scene format's defaults (chain 3, seed 0). The values are
    checked by the program's scene reader, with its messages, when the thermostat is set (a
    Thermostat itself holds them as given). A thermostat runs with method "sesi2". The thermostat
    a simulation reads back (sim.thermostat) has every key of its kind."""

    def __init__(self, kind, temperature, gamma=None, tau=None, chain=None, seed=None):
        self.kind = kind
        self.temperature = temperature
        self.gamma = gamma
        self.tau = tau
        self.chain = chain
        self.seed = seed

    def as_dict(self):
        """The [thermostat] table's keys that are given, as a dict."""
        keys = {"kind": self.kind, "temperature": self.temperature, "gamma": self.gamma, "tau": self.tau,
                "chain": self.chain, "seed": self.seed}
        return {k: v for k, v in keys.items() if v is not None}

    def __eq__(self, other):
        return isinstance(other, Thermostat) and self.as_dict() == other.as_dict()

    def __repr__(self):
        return "sesi.Thermostat(" + ", ".join(f"{k}={v!r}" for k, v in self.as_dict().items()) + ")"


def _thermostat_table(value, where):
    """A thermostat setting as the dict of a [thermostat] table (None stays None)."""
    if value is None:
        return None
    if isinstance(value, Thermostat):
        return value.as_dict()
    if isinstance(value, dict):
        return dict(value)
    raise InputError(f"{where}: expected a sesi.Thermostat, a dict of the [thermostat] keys or None, "
                     f"got {type(value).__name__}")


def _thermostat_of(keys):
    if keys is None:
        return None
    temperature = keys["temperature"]
    if isinstance(temperature, list):
        temperature = [tuple(knot) for knot in temperature]
    return Thermostat(**{**keys, "temperature": temperature})


class Simulation:
    """A scene (space, bodies, potentials, integrator settings) and its state.

    Built with the constructor and add_body / add_potential, or read with from_toml / from_dict
    (the keys of the scene format, docs/scene-format.md). The scene is read and checked as a
    whole, with the program's messages, when the simulation is first used (a state, energy(),
    integrate(), run()); bodies and potentials are fixed from then on, the integrator settings
    (method, dt, energy_guard, threads, check_every) and the thermostat may change between runs.
    """

    def __init__(self, space="sphere", dim=2, radius=None, name=None, box=None, genus=None):
        doc = {"space": {"kind": space, "dim": dim}}
        if radius is not None:
            doc["space"]["radius"] = radius
        # A topology: a periodic box on E^n, a compact surface of genus g on H^2 (the [space] keys).
        if box is not None:
            doc["space"]["box"] = box
        if genus is not None:
            doc["space"]["genus"] = genus
        if name is not None:
            doc["name"] = name
        self._init(doc, "<simulation>")

    def _init(self, doc, source):
        self._doc = doc
        self._doc.setdefault("bodies", [])
        self._doc.setdefault("potential", [])
        self._doc.setdefault("integrator", {})
        self._source = source
        self._functions = []  # (value, gradient) of the Python potentials
        self._core = None
        self._last_rows = None  # the last run()'s rows and why it stopped ("" when complete), for view()
        self._last_status = ""

    # ---- building ------------------------------------------------------------------------

    @classmethod
    def from_dict(cls, doc, source="<dict>"):
        """A simulation of a scene given as a dict with the scene file's keys (space, bodies,
        potential, integrator, name); lists and NumPy arrays for vectors. Checked at once."""
        if not isinstance(doc, dict):
            raise InputError(f"{source}: expected a dict of the scene format's keys, got {type(doc).__name__}")
        sim = cls.__new__(cls)
        sim._init(copy.deepcopy(doc), source)
        sim._start()
        return sim

    @classmethod
    def from_toml(cls, path):
        """A simulation of the scene file at path, read as `sesi run path` reads it (the same
        checks and messages, with file and line)."""
        sim = cls.__new__(cls)
        sim._init({}, str(path))
        sim._core = _Core.from_file(str(path))
        return sim

    @classmethod
    def paper(cls):
        """The seed paper's scene (`sesi run` without a scene): three bodies on S^2, SESI 4 at
        dt = 0.1; its exact solution is sesi.paper_exact(t)."""
        sim = cls.__new__(cls)
        sim._init({}, "<default scene>")
        sim._core = _Core.paper()
        return sim

    def add_body(self, mass=1.0, x=None, v=None, q=None, p=None):
        """Add a body: its mass and either its embedding point x and velocity v, or its chart
        coordinates q and momenta p (docs/scene-format.md, [[bodies]])."""
        self._building("add_body")
        body = {"mass": mass, "x": x, "v": v, "q": q, "p": p}
        self._doc["bodies"].append({k: val for k, val in body.items() if val is not None})

    def add_bodies(self, mass, x=None, v=None, q=None, p=None):
        """Add many bodies: mass a number or one per body, and per-body rows of x and v (or q
        and p), e.g. NumPy arrays of shape (N, n + 1)."""
        rows = x if x is not None else q
        if rows is None:
            raise InputError("add_bodies: give x (with v) or q (with p)")
        count = len(rows)
        masses = [mass] * count if isinstance(mass, (int, float)) else list(mass)
        if len(masses) != count:
            raise InputError(f"add_bodies: {len(masses)} masses for {count} bodies")
        for k in range(count):
            self.add_body(mass=masses[k],
                          x=None if x is None else x[k], v=None if v is None else v[k],
                          q=None if q is None else q[k], p=None if p is None else p[k])

    def add_potential(self, kind=None, value=None, gradient=None, **keys):
        """Add a potential term: a kind of the scene format with its keys, e.g.
        add_potential("cotangent-gravity", G=1.0) (sesi.potentials() lists them); or a Python
        external potential add_potential(value=f, gradient=g) with f(x, m) -> float and
        g(x, m) -> dV/dx on a body's embedding point x (a NumPy vector) and mass m. Python
        potentials are slow (a call per body and force evaluation, on one thread): for
        prototyping."""
        self._building("add_potential")
        if value is not None or gradient is not None:
            if kind is not None or keys:
                raise InputError("add_potential: give either a kind with its keys or value= and gradient=")
            if not callable(value) or not callable(gradient):
                raise InputError("add_potential: value and gradient must both be callables f(x, m)")
            self._functions.append((value, gradient))
            return
        if kind is None:
            raise InputError("add_potential: missing the kind (one of "
                             + ", ".join(k["kind"] for k in potentials()) + ")")
        self._doc["potential"].append({"kind": kind, **keys})

    def _building(self, what):
        if self._core is not None:
            raise InputError(f"{what}: the simulation has started; bodies and potentials are fixed "
                             "(make a new Simulation, e.g. from sim.x and sim.v)")

    def _start(self):
        if self._core is None:
            # Empty tables and lists are absent keys (the reader refuses an empty [[potential]]).
            doc = {k: v for k, v in self._doc.items() if not (isinstance(v, (list, dict)) and len(v) == 0)}
            self._core = _Core(doc, self._source, list(self._functions))
        return self._core

    # ---- settings --------------------------------------------------------------------------

    def _setting(self, key, value):
        if self._core is None:
            self._doc["integrator"][key] = value
            return
        if key == "method":
            self._core.set_method(value)
        elif key == "dt":
            self._core.set_dt(float(value))
        elif key == "energy_guard":
            self._core.set_energy_guard(0.0 if value is False else float(value))
        elif key == "threads":
            self._core.set_threads(int(value))
        elif key == "check_every":
            self._core.set_check_every(int(value))

    def _set_thermostat(self, value):
        table = _thermostat_table(value, "thermostat")
        if table is not None:
            _thermostat_keys(table, self._source)  # checked now, with the scene reader's messages
        if self._core is None:
            if table is None:
                self._doc.pop("thermostat", None)
            else:
                self._doc["thermostat"] = table
            return
        self._core.set_thermostat(table)

    thermostat = property(lambda self: _thermostat_of(self._start().thermostat), _set_thermostat,
                          doc="The thermostat (sesi.Thermostat, or None: constant energy). Set a Thermostat or a dict "
                              "of the [thermostat] keys; it acts from the next step on, at the current state (and the "
                              "energy guard then judges the new thermostat's conserved quantity from there). With a "
                              "thermostat the method is sesi2 (the default then).")

    method = property(lambda self: self._start().method,
                      lambda self, value: self._setting("method", value),
                      doc="The method, a name of sesi.methods() (default sesi4).")
    dt = property(lambda self: self._start().dt,
                  lambda self, value: self._setting("dt", value),
                  doc="The step size (negative integrates backwards).")
    energy_guard = property(None, lambda self, value: self._setting("energy_guard", value),
                            doc="The energy guard's threshold on |E - E0| / (K0 + |V0|), or False.")
    threads = property(None, lambda self, value: self._setting("threads", value),
                       doc="Threads for forces and diagnostics (0: all cores); results do not depend on it.")
    check_every = property(None, lambda self, value: self._setting("check_every", value),
                           doc="Steps between the checks (energy guard, close encounters).")
    auto_reason = property(lambda self: self._start().auto_reason,
                           doc="With method \"auto\" (and tolerance and t_end in the scene): why the method "
                               "and step were picked, as `sesi run` picks them; None otherwise.")

    # ---- state -------------------------------------------------------------------------------

    t = property(lambda self: self._start().t, doc="The time.")
    step = property(lambda self: self._start().step, doc="Steps taken.")
    x = property(lambda self: self._start().x, doc="Embedding points, one row per body.")
    v = property(lambda self: self._start().v, doc="Embedding velocities, one row per body.")
    q = property(lambda self: self._start().q, doc="Chart coordinates (the scene's chart), one row per body.")
    p = property(lambda self: self._start().p, doc="Conjugate momenta, one row per body.")
    masses = property(lambda self: self._start().masses, doc="The bodies' masses.")
    dim = property(lambda self: self._start().dim, doc="The dimension n of the space.")
    space = property(lambda self: self._start().space, doc="sphere, hyperbolic or euclidean.")
    radius = property(lambda self: self._start().radius, doc="R (1 on euclidean).")
    box = property(lambda self: self._start().box,
                   doc="The periodic box's edges [L1, ..., Ln] on E^n (domain [0, L_k) per axis), or None.")
    genus = property(lambda self: self._start().genus,
                     doc="The genus g of the compact hyperbolic surface H^2/Gamma, or None.")
    max_cutoff = property(lambda self: self._start().max_cutoff,
                          doc="The largest pair cutoff the box or surface allows (half the shortest edge; the "
                              "surface's injectivity radius), or None without a topology.")
    image_counts = property(lambda self: self._start().image_counts,
                            doc="In a periodic box: each body's integer image counts n_b, an int64 array of shape "
                                "(bodies, n); the body went to x_b + L * n_b (sim.unwrapped_points). None without a box.")
    words = property(lambda self: self._start().words,
                     doc="On a compact surface: each body's group word W_b as text, the 1-based side numbers "
                         "joined by '.' (\"e\" for the identity), as trajectory.csv's b{k}_word; the body went "
                         "to W_b x_b (sim.unwrapped_points). None without a surface.")
    unwrapped_points = property(lambda self: self._start().unwrapped_points,
                                doc="Where the bodies went in the covering space (E^n, H^2), one row per body: "
                                    "x_b + L * n_b in a box, W_b x_b on a surface (for the MSD); sim.x without a "
                                    "topology. sim.x and sim.q are the bodies in the domain (or past a side by less than "
                                    "the wrap margin, a quarter of the cutoff).")
    momentum_names = property(lambda self: self._start().momentum_names,
                              doc="Names of the momentum map's components (diagnostics.csv's).")

    @property
    def n_bodies(self):
        return self._start().bodies

    def energy(self):
        """The total energy of the current state."""
        return self._start().energy()

    def momentum_map(self):
        """The momentum map (angular momentum in so(n+1), so(n,1), or linear then angular on E^n)."""
        return self._start().momentum_map()

    # ---- running -------------------------------------------------------------------------------

    def integrate(self, t):
        """Advance to time t on the grid of dt (the last step shortened to end at t), with the
        program's checks. Raises InstabilityError (the simulation at its last good state) or
        KeyboardInterrupt (Ctrl-C, between steps)."""
        report = self._start().integrate(float(t))
        self._raise(report, None)

    def run(self, t_end, output_every=1):
        """Advance to t_end as integrate(), and return the rows: every output_every steps of the
        simulation's step count, the current state first and the last state: a dict of NumPy
        arrays t (rows), x, v (rows x bodies x ambient), q, p (rows x bodies x n), energy (rows)
        and momentum (rows x components, named by momentum_names). With a topology also
        unwrapped_points (rows x bodies x ambient), and image_counts (rows x bodies x n, int64) in a
        box or words (a list per row of the bodies' words) on a surface, as trajectory.csv's columns."""
        report, out = self._start().run(float(t_end), int(output_every))
        self._last_rows, self._last_status = out, ""
        self._raise(report, out)
        return out

    def view(self, rows=None, *, max_frames=1000, precision="auto", title=None):
        """The viewer page (a sesi.View) of rows, a dict that run() returned; by default of the
        last run()'s rows (with its failure in a banner when it raised InstabilityError), or,
        before any run, of the current state as one frame. Thinned evenly to at most max_frames
        frames (the first and last kept); precision "auto", 32 or 64 as sesi.view's; title: the
        page's title (default: the scene's name). Speeds come from v and the masses, jumps from
        the image counts or words, the diagnostics from every row's energy."""
        status = ""
        if rows is None and self._last_rows is not None:
            rows, status = self._last_rows, self._last_status
        return _simulation_view(self, rows, max_frames, precision, title, status)

    def _raise(self, report, out):
        if report.complete:
            return
        if report.interrupted:
            raise KeyboardInterrupt
        message = (f"{report.detail} at step {report.failed_step} (t = {report.failed_t:.6g}); the "
                   f"simulation is at its last good state, step {self.step} (t = {self.t:.6g})")
        if out is not None:
            self._last_status = message  # the last run's rows stop here (Simulation.view's banner)
        raise InstabilityError(message, reason=report.reason, detail=report.detail, step=report.failed_step,
                               t=report.failed_t, body=report.failed_body, output=out)

    def __repr__(self):
        if self._core is None:
            return (f"<sesi.Simulation {self._doc['space'].get('kind')} {self._doc['space'].get('dim')}, "
                    f"{len(self._doc['bodies'])} bodies, not started>")
        topology = (f", box {self.box}" if self.box is not None else "") + \
            (f", genus {self.genus}" if self.genus is not None else "")
        return (f"<sesi.Simulation {self.space} {self.dim}{topology}, {self.n_bodies} bodies, t = {self.t:.6g}, "
                f"method {self.method}>")
