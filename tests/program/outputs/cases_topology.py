# The outputs of a run on a topology (issue #26; docs/scene-format.md, Outputs): trajectory.csv's
# image counts (E^n box) or unwrapped points and words (H^2 surface), summary.json's space, and
# the H5MD layout (check_h5md.py checks it against the CSV). Checkpoints on a topology are in
# run/cases_checkpoint_topology.py, which uses the scenes written here.
# Exec'd in check_program.py's namespace: case, check, Context, ... come from there.

TOPOLOGY_EPS = 2.0 ** -52


def topology_box_scene(edges, bodies, *, lj=True, dt=0.005, t_end=10.0, output_every=50, method="sesi2",
                       thermostat=""):
    """An E^n periodic box with bodies [(q, p)], Lennard-Jones (cutoff 2.5) unless lj is False."""
    lines = ['name = "topology-box"', "[space]", 'kind = "euclidean"', f"dim = {len(edges)}",
             f"box = [{', '.join(map(repr, edges))}]"]
    for q, p in bodies:
        lines += ["[[bodies]]", "mass = 1.0", f"q = [{', '.join(map(repr, q))}]", f"p = [{', '.join(map(repr, p))}]"]
    if lj:
        lines += ["[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5"]
    lines += ["[integrator]", f'method = "{method}"', f"dt = {dt!r}", f"t_end = {t_end!r}",
              f"output_every = {output_every}"]
    return "\n".join(lines) + "\n" + thermostat


def topology_box_lattice(edges=(8.0, 7.0), per_side=4, speed=1.0, seed=3):
    """per_side^2 bodies on a grid in a 2-D box, random momenta (deviation `speed`)."""
    import random
    rng = random.Random(seed)
    bodies = []
    for i in range(per_side):
        for j in range(per_side):
            q = [(i + 0.5) * edges[0] / per_side, (j + 0.5) * edges[1] / per_side]
            bodies.append((q, [rng.gauss(0.0, speed), rng.gauss(0.0, speed)]))
    return bodies


def topology_surface_point(radius, r, phi, speed, heading):
    """x and v on the hyperboloid of radius R (time-like last): the point at distance r, polar angle
    phi, moving at `speed` at the angle `heading` from the outward radial direction."""
    c, s = math.cosh(r / radius), math.sinh(r / radius)
    x = [radius * s * math.cos(phi), radius * s * math.sin(phi), radius * c]
    e_r = [c * math.cos(phi), c * math.sin(phi), s]  # unit tangent vectors (Minkowski norm 1)
    e_phi = [-math.sin(phi), math.cos(phi), 0.0]
    v = [speed * (math.cos(heading) * a + math.sin(heading) * b) for a, b in zip(e_r, e_phi)]
    return x, v


def topology_surface_scene(radius, bodies, *, genus=2, lj_cutoff=None, dt=0.01, t_end=10.0, output_every=25,
                           method="sesi2", thermostat=""):
    """A compact hyperbolic surface of genus g with bodies [(x, v)], Lennard-Jones with the given cutoff
    if any."""
    lines = ['name = "topology-surface"', "[space]", 'kind = "hyperbolic"', "dim = 2", f"radius = {radius!r}",
             f"genus = {genus}"]
    for x, v in bodies:
        lines += ["[[bodies]]", "mass = 1.0", f"x = [{', '.join(map(repr, x))}]", f"v = [{', '.join(map(repr, v))}]"]
    if lj_cutoff is not None:
        lines += ["[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", f"cutoff = {lj_cutoff!r}"]
    lines += ["[integrator]", f'method = "{method}"', f"dt = {dt!r}", f"t_end = {t_end!r}",
              f"output_every = {output_every}"]
    return "\n".join(lines) + "\n" + thermostat


def topology_surface_ring(radius, count=8, speed=1.0, seed=5):
    """One body near the polygon's centre and `count` on a circle about it (well inside the genus-2
    polygon, whose inradius is acosh(cot(pi/8)) R = 1.53 R), at random headings."""
    import random
    rng = random.Random(seed)
    bodies = [topology_surface_point(radius, 0.2 * radius, 1.0, speed, rng.uniform(0, 2 * math.pi))]
    for k in range(count):
        bodies.append(topology_surface_point(radius, 0.7 * radius, 2 * math.pi * (k + 0.25) / count, speed,
                                             rng.uniform(0, 2 * math.pi)))
    return bodies


def topology_generators(genus, radius):
    """generator(k), k = 0..4g-1, as docs/topology.md and include/sesi/topologies/hyperbolic_surface.hpp
    define them (Sausset & Tarjus 2007): the boost along the direction 2 pi k / 4g by twice the inradius
    rho, cosh(rho / R) = cot(pi / 4g); 3x3 lists acting on (x1, x2, x0)."""
    sides = 4 * genus
    d = 2 * math.acosh(1 / math.tan(math.pi / sides))
    ch, sh = math.cosh(d), math.sinh(d)
    out = []
    for k in range(sides):
        c, s = math.cos(2 * math.pi * k / sides), math.sin(2 * math.pi * k / sides)
        # R(theta) Boost_x(d) R(-theta)
        out.append([[1 + (ch - 1) * c * c, (ch - 1) * c * s, sh * c],
                    [(ch - 1) * c * s, 1 + (ch - 1) * s * s, sh * s],
                    [sh * c, sh * s, ch]])
    return out


def topology_apply_word(generators, word, x):
    """element(word) x = g_{w1} g_{w2} ... g_{wm} x (the word's letters left to right), the letters
    parsed from the output text ("e", or 1-based sides joined by '.'); also the product of the
    matrices' max-norms, which bounds how rounding grows through the product."""
    letters = [] if word == "e" else [int(s) - 1 for s in word.split(".")]
    growth = 1.0
    for letter in reversed(letters):
        g = generators[letter]
        x = [sum(g[i][j] * x[j] for j in range(3)) for i in range(3)]
        growth *= max(sum(abs(v) for v in row) for row in g)
    return x, letters, growth


def topology_csv(out):
    lines = (pathlib.Path(out) / "trajectory.csv").read_text().splitlines()
    return lines[0].split(","), [line.split(",") for line in lines[1:]]


@case
def topology_box_outputs(ctx):
    edges = [8.0, 7.0]
    path = ctx.write("box.toml", topology_box_scene(edges, topology_box_lattice(edges)))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--out", out, "--quiet"), "box run")
    header, rows = topology_csv(out)
    n = 16
    expected = ["t"]
    for b in range(1, n + 1):
        expected += [f"b{b}_{c}{i}" for c in "qpxn" for i in (1, 2)]
    check(header == expected, f"header {header}")
    s = summary(out)
    check(s["space"]["box"] == edges and s["space"]["max_cutoff"] == 3.5,
          f"summary space {s['space']}: expected the box and half its shortest edge")
    check("genus" not in s["space"], "a box run's summary has a genus")
    # Between wraps a body may stand outside the box by up to the wrap margin, a quarter of the
    # cutoff (docs/scene-format.md, [space]).
    margin = 0.25 * 2.5
    crossed = 0
    previous = None
    for row in rows:
        check(len(row) == len(header), "a row's length differs from the header's")
        unwrapped = []
        for b in range(n):
            base = 1 + 8 * b
            x = [float(v) for v in row[base + 4:base + 6]]
            counts = row[base + 6:base + 8]
            check(all(c.lstrip("-").isdigit() for c in counts), f"image counts {counts} are not integers")
            counts = [int(c) for c in counts]
            crossed += any(counts)
            check(all(-margin <= x[k] <= edges[k] + margin for k in range(2)), f"body {b + 1} at {x}, out of the box")
            unwrapped.append([x[k] + edges[k] * counts[k] for k in range(2)])
        if previous is not None:
            # One row apart (50 steps of 0.005) a body moves far less than half an edge: with the
            # counts the unwrapped path is continuous, across every side it crossed.
            for b in range(n):
                jump = max(abs(unwrapped[b][k] - previous[b][k]) for k in range(2))
                check(jump < 0.5 * min(edges), f"body {b + 1}'s unwrapped position jumps by {jump}")
        previous = unwrapped
    check(crossed > 0, "no body crossed a side: the case tests nothing")
    final = s["final_state"]["bodies"]
    check([body["n"] for body in final] == [[float(c) for c in rows[-1][1 + 8 * b + 6:1 + 8 * b + 8]]
                                            for b in range(n)], "the summary's final image counts differ from the CSV's")


@case
def topology_box_free_bodies_unwrap_exactly(ctx):
    # Free bodies in a small box cross its sides many times; their unwrapped positions x + L n are
    # the straight lines q0 + p t / m. sesi2 drifts q by h p / m per step: each drift and each
    # reduction by L rounds once, at most eps/2 of |q| <= L + margin + h |p| (< 4 here), so after
    # k steps the error is below 2 k eps 4 (two roundings a step, with room for the product h p),
    # plus eps |u|: eps/2 |u| for the sum x + L n and as much for the reference q0 + p t.
    edges, dt, t_end = [3.0, 2.0], 0.01, 20.0
    bodies = [([1.0, 1.0], [1.3, 0.7]), ([0.2, 1.9], [-0.9, 2.1]), ([2.5, 0.1], [0.0, -1.7])]
    path = ctx.write("free.toml", topology_box_scene(edges, bodies, lj=False, dt=dt, t_end=t_end, output_every=100))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--out", out, "--quiet"), "free box run")
    _, rows = topology_csv(out)
    worst, crossings = 0.0, 0
    for row in rows:
        t = float(row[0])
        steps = round(t / dt)
        for b, (q0, p) in enumerate(bodies):
            base = 1 + 8 * b
            x = [float(v) for v in row[base + 4:base + 6]]
            counts = [int(c) for c in row[base + 6:base + 8]]
            crossings = max(crossings, sum(abs(c) for c in counts))
            for k in range(2):
                u = x[k] + edges[k] * counts[k]
                exact = q0[k] + p[k] * t
                bound = 2 * steps * TOPOLOGY_EPS * 4 + TOPOLOGY_EPS * abs(u)
                worst = max(worst, abs(u - exact) / bound)
    check(crossings >= 10, f"only {crossings} crossings")
    check(worst <= 1.0, f"unwrapped positions off the straight lines by {worst} of the rounding bound")


@case
def topology_surface_outputs(ctx):
    radius = 2.0
    path = ctx.write("surface.toml", topology_surface_scene(radius, topology_surface_ring(radius), t_end=12.0))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--out", out, "--quiet"), "surface run")
    header, rows = topology_csv(out)
    n = 9
    expected = ["t"]
    for b in range(1, n + 1):
        expected += [f"b{b}_{c}{i}" for c, count in (("q", 2), ("p", 2), ("x", 3), ("u", 3)) for i in range(1, count + 1)]
        expected.append(f"b{b}_word")
    check(header == expected, f"header {header}")
    s = summary(out)
    check(s["space"]["genus"] == 2 and "box" not in s["space"] and s["space"]["max_cutoff"] > 0,
          f"summary space {s['space']}")
    generators = topology_generators(2, radius)
    longest = 0
    previous = None
    for row in rows:
        for b in range(n):
            base = 1 + 11 * b
            x = [float(v) for v in row[base + 4:base + 7]]
            u = [float(v) for v in row[base + 7:base + 10]]
            word = row[base + 10]
            check(word == "e" or all(s.isdigit() and 1 <= int(s) <= 8 for s in word.split(".")), f"word {word!r}")
            wx, letters, growth = topology_apply_word(generators, word, x)
            longest = max(longest, len(letters))
            # The word is freely reduced: no letter beside its inverse (side k + 2g mod 4g).
            check(all((a - c) % 8 != 4 for a, c in zip(letters, letters[1:])), f"word {word} is not reduced")
            # u = W x, both computed in doubles by matrix products of the generators: each of the m
            # products rounds to eps relative to its entries, which the norms' product bounds.
            bound = 8 * (len(letters) + 1) * TOPOLOGY_EPS * growth * max(abs(v) for v in x)
            err = max(abs(a - c) for a, c in zip(wx, u))
            check(err <= bound, f"body {b + 1}: u differs from its word times x by {err} (bound {bound}), word {word}")
            # One row apart (25 steps of 0.01 at speed 1) u moves by about 0.25 along a continuous
            # path; an image taken wrongly would move it by a translation of the group, at least
            # the systole 2 acosh(1 + sqrt 2) R = 6.1 (Bolza): the check is d < systole / 2.
            if previous is not None:
                p = previous[b]
                cosh_d = (p[2] * u[2] - p[0] * u[0] - p[1] * u[1]) / radius ** 2
                d = radius * math.acosh(max(1.0, cosh_d))
                check(d < radius * math.acosh(1 + math.sqrt(2)), f"body {b + 1}'s unwrapped point jumps by {d}")
        previous = [[float(v) for v in row[1 + 11 * b + 7:1 + 11 * b + 10]] for b in range(n)]
    check(longest >= 2, f"words of at most {longest} letters: the bodies did not cross sides")
    final = s["final_state"]["bodies"]
    check([body["word"] for body in final] == [rows[-1][1 + 11 * b + 10] for b in range(n)],
          "the summary's final words differ from the CSV's")


@case
def topology_box_less_outputs_unchanged(ctx):
    # Without a topology nothing of the outputs changes: no new columns, no new summary keys.
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "1", "--out", out, "--quiet"), "default run")
    header, _ = topology_csv(out)
    check(not any(name.endswith(("_n1", "_u1", "_word")) for name in header), f"header {header}")
    s = summary(out)
    check(sorted(s["space"]) == ["dim", "kind", "radius"], f"space {s['space']}")
    check(all(sorted(b) == ["p", "q", "v", "x"] for b in s["final_state"]["bodies"]), "final state keys")
