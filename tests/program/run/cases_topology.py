# Runs on a space with a topology (issue #26; docs/topology.md): a Lennard-Jones liquid in an E^2
# periodic box and on a genus-2 surface runs to the end, the same to the bit on 1 and 2 threads,
# with the bodies given outside the domain reduced into it at the start and kept near it; a bound
# dimer crossing the box's faces and the polygon's sides many times conserves energy at the
# method's order (a wrong minimum image or wrap would show as jumps that do not shrink with the
# step). Exec'd in check_program.py's namespace (names prefixed topology_run_); expect_same_files
# comes from run/cases_threads.py.

import random

# Lennard-Jones (epsilon = sigma = 1): the minimum r0 = 2^(1/6), the curvature there
# V''(r0) = 36 * 2^(2/3) = 57.15, so a dimer of unit masses (reduced mass 1/2) vibrates at
# omega = sqrt(2 * 57.15) = 10.7.
TOPOLOGY_RUN_R0 = 2.0 ** (1.0 / 6.0)
TOPOLOGY_RUN_OMEGA = math.sqrt(2.0 * 36.0 * 2.0 ** (2.0 / 3.0))


def topology_run_scene(space, bodies, method, dt, t_end, output_every, cutoff="2.5"):
    lines = ["[space]", *space]
    for x, v in bodies:
        lines += ["[[bodies]]", "mass = 1.0", f"x = [{', '.join(map(repr, x))}]", f"v = [{', '.join(map(repr, v))}]"]
    lines += ["[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", f"cutoff = {cutoff}",
              "[integrator]", f'method = "{method}"', f"dt = {dt}", f"t_end = {t_end}", f"output_every = {output_every}"]
    return "\n".join(lines) + "\n"


def topology_run_rows(path, columns):
    """The named columns of a CSV file, one list per row."""
    lines = pathlib.Path(path).read_text().splitlines()
    header = lines[0].split(",")
    index = [header.index(c) for c in columns]
    return header, [[float(line.split(",")[k]) for k in index] for line in lines[1:]]


# ---- the box ------------------------------------------------------------------------------------

def topology_run_box_liquid(n_side, spacing, speed, seed):
    """n_side^2 bodies on a square lattice of the given spacing filling an E^2 box of edge
    n_side * spacing, the lattice shifted by half the box so that half the bodies are given
    outside [0, L) (and one exactly on the far face x = L), random velocities."""
    rng = random.Random(seed)
    edge = n_side * spacing
    bodies = []
    for i in range(n_side * n_side):
        x = [(i % n_side) * spacing - edge / 2.0, (i // n_side + 0.5) * spacing - edge / 2.0]
        bodies.append((x, [rng.gauss(0.0, speed), rng.gauss(0.0, speed)]))
    # Body n_side/2 + 1 sits at x_1 = 0: give it on the far face x_1 = L instead, the same point.
    face = n_side // 2
    bodies[face] = ([edge, bodies[face][0][1]], bodies[face][1])
    return edge, bodies


@case
def topology_run_box_liquid_threads(ctx):
    """256 Lennard-Jones bodies in an E^2 box at density 0.69, 400 steps of sesi2: the run
    completes with an energy error of order 2, bodies start reduced into [0, L) and stay within
    the wrap's margin of it, and 1 and 2 threads write the same bytes."""
    edge, bodies = topology_run_box_liquid(16, 1.2, 0.7, 41)
    space = ['kind = "euclidean"', "dim = 2", f"box = [{edge!r}, {edge!r}]"]
    scene = ctx.write("box-liquid.toml", topology_run_scene(space, bodies, "sesi2", "0.005", "2.0", 40))
    outs = {}
    for threads in (1, 2):
        outs[threads] = ctx.work / f"box-{threads}"
        expect_ok(ctx.run("run", scene, "--threads", threads, "--out", outs[threads], "--quiet"), f"box on {threads} threads")
        check(summary(outs[threads])["complete"] is True, f"box on {threads} threads: not complete")
    expect_same_files(outs[2], outs[1], "box liquid: --threads 2 against --threads 1")
    topology_run_liquid_order(ctx, "box", scene, outs[1], 0.005, 40)
    n = len(bodies)
    columns = [f"b{b + 1}_x{k + 1}" for b in range(n) for k in range(2)]
    _, rows = topology_run_rows(outs[1] / "trajectory.csv", columns)
    # Row 0: each given point reduced into [0, L) per axis, x - L floor(x / L) (Python's %, exact
    # but for the product and difference the program rounds: 2 ulp of L).
    for b, (x, _) in enumerate(bodies):
        for k in range(2):
            got, want = rows[0][2 * b + k], x[k] % edge
            if want == edge:
                want = 0.0
            check(0.0 <= got < edge, f"body {b + 1} axis {k + 1} starts at {got!r}, outside [0, {edge!r})")
            check(abs(got - want) <= 4e-16 * edge, f"body {b + 1} axis {k + 1} starts at {got!r}, expected {want!r}")
    face = 2 * (16 // 2)
    check(bodies[16 // 2][0][0] == edge and rows[0][face] == 0.0,
          f"the body given on the face x = L starts at {rows[0][face]!r}, expected 0")
    # Every row: within the wrap's margin (a quarter of the cutoff) of the box; the bodies move
    # ~1.4 over the run, past the margin, so reductions happen (their image counts change).
    margin = 0.25 * 2.5
    for r, row in enumerate(rows):
        worst = max(max(-c, c - edge) for c in row)
        check(worst <= margin, f"row {r}: a body is {worst:.3g} outside the box, more than the margin {margin}")
    header, counts = topology_run_rows(outs[1] / "trajectory.csv", [f"b{b + 1}_n{k + 1}" for b in range(n) for k in range(2)])
    crossed = sum(1 for c in counts[-1] if c != 0)
    check(crossed >= 5, f"only {crossed} image counts changed: few bodies crossed a face, the run tests little")


def topology_run_liquid_order(ctx, name, scene, out, dt, every):
    """The liquid of `scene` at dt (its run in `out`) and at dt/2, sampled at the same times: sesi2's
    max energy error falls by 4. The truncation's force jump at the cutoff (0.039 epsilon/sigma)
    adds O(h) per pair crossing, of random sign: ~0.04 v h per crossing, some 10^3 crossings in
    these runs, sqrt(10^3) 0.04 v h ~ 5-10% of the h^2 term here (measured: 0.058 at h = 0.005 in
    the box), so the ratio lies within 4 (1 -+ 0.1) / (1 -+ 0.2) ~ [3.3, 5]: asserted [3, 5.33]."""
    half = ctx.work / f"{name}-half"
    expect_ok(ctx.run("run", scene, "--dt", repr(dt / 2), "--output-every", 2 * every, "--out", half, "--quiet"),
              f"{name} at dt/2")
    (t1, e1), (t2, e2) = topology_run_energy_errors(out), topology_run_energy_errors(half)
    check(t1 == t2, f"{name}: the runs at dt and dt/2 have rows at other times")
    check(3.0 <= e1 / e2 <= 16.0 / 3.0, f"{name}: max energy errors {e1:.3g} (dt) and {e2:.3g} (dt/2): ratio {e1 / e2:.3g}, expected 4")


# ---- the surface --------------------------------------------------------------------------------

def topology_run_polygon(genus):
    """The regular 4g-gon of interior angles pi/(2g) (Sausset & Tarjus 2007): cosh of its inradius
    cot(pi/4g) and of its circumradius cot^2(pi/4g), in radii."""
    c = 1.0 / math.tan(math.pi / (4 * genus))
    return math.acosh(c), math.acosh(c * c)


def topology_run_inside(x, radius, genus, slack):
    """Whether the hyperboloid point x is in the polygon D, up to slack (a length): each side k,
    at distance inradius along the angle 2 pi k/4g, bounds the half-plane
    x1 cos a_k + x2 sin a_k <= tanh(inradius) x0 (the side's geodesic in the hyperboloid model)."""
    inradius, _ = topology_run_polygon(genus)
    t = math.tanh(inradius + slack / radius)
    return all(x[0] * math.cos(2 * math.pi * k / (4 * genus)) + x[1] * math.sin(2 * math.pi * k / (4 * genus))
               <= t * x[2] * (1 + 1e-12) for k in range(4 * genus))


def topology_run_boost(angle, rapidity):
    """The Lorentz boost by `rapidity` along the direction `angle` of H^2 (time-like last)."""
    c, s, ca, sa = math.cosh(rapidity), math.sinh(rapidity), math.cos(angle), math.sin(angle)

    def apply(y):
        along = y[0] * ca + y[1] * sa
        across = -y[0] * sa + y[1] * ca
        along, t = c * along + s * y[2], s * along + c * y[2]
        return [along * ca - across * sa, along * sa + across * ca, t]
    return apply


def topology_run_surface_liquid(radius, count, seed, speed):
    """count bodies placed at random in the disc of the polygon's inradius (less 0.3), at least
    1.1 sigma apart (random sequential addition), with random tangent velocities."""
    rng = random.Random(seed)
    inradius, _ = topology_run_polygon(2)
    reach = inradius * radius - 0.3
    points = []
    while len(points) < count:
        # Uniform in area: cosh(rho/R) uniform in [1, cosh(reach/R)].
        rho = radius * math.acosh(1.0 + rng.random() * (math.cosh(reach / radius) - 1.0))
        phi = rng.uniform(0.0, 2.0 * math.pi)
        x = [radius * math.sinh(rho / radius) * math.cos(phi), radius * math.sinh(rho / radius) * math.sin(phi),
             radius * math.cosh(rho / radius)]
        # Geodesic distance: cosh(d/R) = -<x, y>_L / R^2.
        if all(radius * math.acosh(max(1.0, (y[2] * x[2] - y[0] * x[0] - y[1] * x[1]) / radius ** 2)) >= 1.1
               for y in points):
            points.append(x)
    bodies = []
    for x in points:
        v = [rng.gauss(0.0, speed) for _ in range(3)]
        dot = (v[0] * x[0] + v[1] * x[1] - v[2] * x[2]) / (-radius * radius)
        bodies.append((x, [a - dot * b for a, b in zip(v, x)]))
    return bodies


@case
def topology_run_surface_liquid_threads(ctx):
    """80 Lennard-Jones bodies on the genus-2 surface of radius 5 (density 0.25), 400 steps of
    sesi2 (energy error of order 2): complete, every body starts in the polygon and stays within the wrap's margin of it,
    and 1 and 2 threads write the same bytes."""
    radius = 5.0
    bodies = topology_run_surface_liquid(radius, 80, 43, 0.7)
    space = ['kind = "hyperbolic"', "dim = 2", f"radius = {radius!r}", "genus = 2"]
    scene = ctx.write("surface-liquid.toml", topology_run_scene(space, bodies, "sesi2", "0.005", "2.0", 40))
    outs = {}
    for threads in (1, 2):
        outs[threads] = ctx.work / f"surface-{threads}"
        expect_ok(ctx.run("run", scene, "--threads", threads, "--out", outs[threads], "--quiet"),
                  f"surface on {threads} threads")
        check(summary(outs[threads])["complete"] is True, f"surface on {threads} threads: not complete")
    expect_same_files(outs[2], outs[1], "surface liquid: --threads 2 against --threads 1")
    topology_run_liquid_order(ctx, "surface", scene, outs[1], 0.005, 40)
    n = len(bodies)
    _, rows = topology_run_rows(outs[1] / "trajectory.csv", [f"b{b + 1}_x{k + 1}" for b in range(n) for k in range(3)])
    margin = 0.25 * 2.5
    for r, row in enumerate(rows):
        for b in range(n):
            check(topology_run_inside(row[3 * b:3 * b + 3], radius, 2, margin if r else 0.0),
                  f"row {r}: body {b + 1} is outside the polygon" + (f" by more than the margin {margin}" if r else ""))
    # Some bodies were brought back through a side: their group words (trajectory.csv) are not "e".
    header, _ = topology_run_rows(outs[1] / "trajectory.csv", [])
    words = pathlib.Path(outs[1] / "trajectory.csv").read_text().splitlines()[-1].split(",")
    wrapped = [b for b in range(n) if words[header.index(f"b{b + 1}_word")] != "e"]
    check(len(wrapped) >= 3, f"only {len(wrapped)} bodies crossed a side: the run tests little")


# ---- a dimer crossing sides: energy error at the method's order -----------------------------------

def topology_run_energy_errors(out):
    _, rows = topology_run_rows(out / "diagnostics.csv", ["t", "energy_error"])
    return [t for t, _ in rows], max(abs(e) for _, e in rows)


def topology_run_order(ctx, name, space, bodies, t_end, cutoff):
    """sesi4 at h and h/2, sampled at the same times: the max relative energy error falls by 2^4.
    Returns the two runs' directories."""
    h = 0.01  # h omega = 0.11
    errors, times, outs = [], [], []
    for k, (dt, every) in enumerate(((h, 10), (h / 2, 20))):
        scene = ctx.write(f"{name}-{k}.toml", topology_run_scene(space, bodies, "sesi4", repr(dt), t_end, every, cutoff))
        out = ctx.work / f"{name}-{k}"
        expect_ok(ctx.run("run", scene, "--out", out, "--quiet"), f"{name} at dt = {dt}")
        t, e = topology_run_energy_errors(out)
        times.append(t)
        errors.append(e)
        outs.append(out)
    check(times[0] == times[1], f"{name}: the two runs' rows are not at the same times")
    ratio = errors[0] / errors[1]
    # Order 4: the error is C h^4 (1 + O((h omega)^2)), (h omega)^2 = 0.013 at h = 0.01; the band
    # 2^4 (1 -+ 0.25) allows that next term a coefficient up to 20. A minimum image or a wrap that
    # is wrong on a side gives an error that does not shrink with h (ratio near 1).
    check(12.0 <= ratio <= 20.0,
          f"{name}: max energy errors {errors[0]:.3g} (h) and {errors[1]:.3g} (h/2), ratio {ratio:.3g}, expected 16")
    # (energy_error is E - E0.) Far above round-off: |E| ~ 1, 4000 steps of ~1e-16 each add up
    # to ~1e-13 at worst.
    check(errors[1] > 1e-10, f"{name}: the error at h/2, {errors[1]:.3g}, is at round-off: the test sees nothing")
    return outs


@case
def topology_run_box_dimer_order(ctx):
    """A bound Lennard-Jones dimer given outside the box (edge 8), moving diagonally at speed 0.8
    for t = 20: it crosses the faces ~3 times each way, half of it on each side each time."""
    a = TOPOLOGY_RUN_R0 / 2.0 * 1.05  # stretched 5%: it vibrates
    centre, u = [-3.0, 9.5], [0.7, 0.45]
    bodies = [([centre[0] - a, centre[1]], u), ([centre[0] + a, centre[1]], u)]
    space = ['kind = "euclidean"', "dim = 2", "box = [8.0, 8.0]"]
    outs = topology_run_order(ctx, "box-dimer", space, bodies, "20", "2.5")
    _, rows = topology_run_rows(outs[0] / "trajectory.csv", ["b1_x1", "b1_x2", "b2_x1", "b2_x2"])
    check(all(0.0 <= c < 8.0 for c in rows[0]), f"the dimer starts at {rows[0]}, not reduced into [0, 8)")
    check(any(abs(r[0] - r[2]) > 4.0 for r in rows), "the dimer never straddles a face at an output row")


@case
def topology_run_surface_dimer_order(ctx):
    """A bound Lennard-Jones dimer on the genus-2 surface of radius 3, given 1.2 circumradii from
    the centre (outside the polygon, in a neighbouring tile), moving at speed 0.8 for t = 30:
    it crosses sides several times."""
    radius = 3.0
    _, circumradius = topology_run_polygon(2)
    a = TOPOLOGY_RUN_R0 / 2.0 * 1.05 / radius  # half the separation, in radii
    u, d = 0.8, 0.05
    move = topology_run_boost(0.3, 1.2 * circumradius)
    bodies = []
    for sign in (-1.0, 1.0):
        x = [sign * radius * math.sinh(a), 0.0, radius * math.cosh(a)]
        v = [-sign * d * math.cosh(a), u, -d * math.sinh(a)]  # tangent: <x, v>_L = 0
        bodies.append((move(x), move(v)))
    space = ['kind = "hyperbolic"', "dim = 2", f"radius = {radius!r}", "genus = 2"]
    outs = topology_run_order(ctx, "surface-dimer", space, bodies, "30", "2.5")
    _, rows = topology_run_rows(outs[0] / "trajectory.csv", [f"b{b}_x{k}" for b in (1, 2) for k in (1, 2, 3)])
    for b in range(2):
        check(not topology_run_inside(bodies[b][0], radius, 2, 0.0), f"body {b + 1} is not given outside the polygon")
        check(topology_run_inside(rows[0][3 * b:3 * b + 3], radius, 2, 0.0), f"body {b + 1} does not start in the polygon")
    # Sides crossed: some output row has the two bodies of the dimer on far sides of the polygon
    # (more than the inradius apart in the chart, while the dimer is 1.2 sigma long).
    inradius, _ = topology_run_polygon(2)
    far = [r for r in rows if radius * math.acosh(max(1.0, (r[2] * r[5] - r[0] * r[3] - r[1] * r[4]) / radius ** 2))
           > inradius * radius]
    check(far, "the dimer never straddles a side at an output row")


@case
def topology_run_auto_picks_a_composition(ctx):
    """method = "auto" on a topology chooses among the plain chart compositions only (the
    processed and geodesic candidates are left out), and the run meets its tolerance."""
    a = TOPOLOGY_RUN_R0 / 2.0 * 1.05
    bodies = [([1.0 - a, 2.0], [0.7, 0.45]), ([1.0 + a, 2.0], [0.7, 0.45])]
    for name, space in (("box", ['kind = "euclidean"', "dim = 2", "box = [8.0, 8.0]"]),
                        ("surface", ['kind = "hyperbolic"', "dim = 2", "radius = 3.0", "genus = 2"])):
        if name == "surface":
            bodies = [([r * 3.0 * math.sinh(a / 3.0), 0.0, 3.0 * math.cosh(a / 3.0)], [0.0, 0.8, 0.0]) for r in (-1.0, 1.0)]
        text = topology_run_scene(space, bodies, "auto", "0.01", "10", 10).replace("dt = 0.01\n", "tolerance = 1e-6\n")
        scene = ctx.write(f"auto-{name}.toml", text)
        out = ctx.work / f"auto-{name}"
        expect_ok(ctx.run("run", scene, "--out", out, "--quiet"), f"auto on the {name}")
        s = summary(out)
        check(s["method"] in METHODS, f"auto on the {name} picked {s['method']!r}, not a plain chart composition")
        tried = [c["method"] for c in s["auto"]["candidates"]]
        check(tried and all(m in METHODS for m in tried), f"auto on the {name} tried {tried}")
        check(s["energy"]["max_rel_error"] <= 1e-6, f"auto on the {name}: error {s['energy']['max_rel_error']:.3g} > 1e-6")


@case
def topology_run_encounter_across_a_side(ctx):
    """The close-encounter check measures the minimum image: two bodies (Lennard-Jones with
    epsilon = 0, so they fly freely; min_distance 0.3) that meet across a box face or a polygon
    side stop the run (exit 3) naming them, where in the cover they are far apart."""
    radius = 3.0
    inradius, _ = topology_run_polygon(2)

    def on_axis(rho, speed):
        """The point rho along the first axis of H^2 of radius 3, moving along it at speed."""
        a = rho / radius
        return ([radius * math.sinh(a), 0.0, radius * math.cosh(a)], [speed * math.cosh(a), 0.0, speed * math.sinh(a)])

    cases = (
        ("box", ['kind = "euclidean"', "dim = 2", "box = [8.0, 8.0]"],
         [([0.5, 4.0], [-1.0, 0.0]), ([7.5, 4.0], [1.0, 0.0])]),
        # Across side 0: one body inside it, one outside it (reduced at the start to the opposite side).
        ("surface", ['kind = "hyperbolic"', "dim = 2", f"radius = {radius!r}", "genus = 2"],
         [on_axis(inradius * radius - 0.5, 1.0), on_axis(inradius * radius + 0.5, -1.0)]),
    )
    for name, space, bodies in cases:
        text = topology_run_scene(space, bodies, "sesi2", "0.01", "1.0", 10, "1.0").replace(
            'epsilon = 1.0', 'epsilon = 0.0\nmin_distance = 0.3')
        scene = ctx.write(f"encounter-{name}.toml", text)
        result = ctx.run("run", scene, "--out", ctx.work / f"encounter-{name}", "--quiet")
        check(result.returncode == 3, f"{name}: exit status {result.returncode}, expected 3 (a close encounter); "
                                      f"stderr: {result.stderr.strip()}")
        check("close encounter: bodies 1 and 2" in result.stderr, f"{name}: {result.stderr.strip()}")
