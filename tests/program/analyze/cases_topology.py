# `sesi analyze` on a periodic box (E^n) and a compact surface (H^2, genus g) (issue #26;
# src/analysis, docs/observables.md): the topology comes from summary.json, g(r) stops at the
# largest allowed cutoff (and refuses more, naming it), and the MSD of bodies moving freely across
# the sides, from the image counts or the words, is (v t)^2. The library's numbers (ideal gas,
# ghost images against all pairs) are tested in test_analysis.cpp.

EPS = 2.0 ** -52


def free_box_scene(trajectory_format="csv"):
    """Free bodies in a 3 x 4 box of E^2, fast enough to cross the faces many times."""
    bodies = [(1.0, [0.5, 3.9], [0.7, -0.45]), (2.0, [2.9, 0.1], [-0.4, 2.6]), (0.5, [1.4, 2.2], [0.6, 0.25])]
    lines = ['name = "box-free"', "[space]", 'kind = "euclidean"', "dim = 2", "box = [3.0, 4.0]"]
    for mass, q, p in bodies:
        lines += ["[[bodies]]", f"mass = {mass!r}", f"q = {q!r}", f"p = {p!r}"]
    lines += ["[integrator]", 'method = "sesi2"', "dt = 0.05", "t_end = 20.0", "output_every = 10",
              f'trajectory_format = "{trajectory_format}"']
    speeds2 = [sum((c / mass) ** 2 for c in p) for mass, _, p in bodies]
    return "\n".join(lines) + "\n", speeds2


def free_surface_scene(trajectory_format="csv"):
    """Free bodies on the genus-2 surface of radius 1.3, each moving away from the chart's origin
    along its ray (p_2 = 0 in the hierarchical chart: the Strang step is then the exact geodesic
    flow, up to rounding, as K_1 and K_2 commute on it; tests/core/topology.cpp), given by
    embedding points and velocities v = speed (cosh r cos phi, cosh r sin phi, sinh r)."""
    radius = 1.3
    starts = [(0.3, 0.4, 0.9), (0.5, 2.5, 1.3), (0.2, -1.0, 1.7)]  # (r, phi, speed)
    lines = ['name = "surface-free"', "[space]", 'kind = "hyperbolic"', "dim = 2", f"radius = {radius!r}",
             "genus = 2"]
    speeds2 = []
    for r, phi, speed in starts:
        x = [radius * math.sinh(r) * math.cos(phi), radius * math.sinh(r) * math.sin(phi), radius * math.cosh(r)]
        v = [speed * math.cosh(r) * math.cos(phi), speed * math.cosh(r) * math.sin(phi), speed * math.sinh(r)]
        speeds2.append(speed * speed)
        lines += ["[[bodies]]", "mass = 1.0", f"x = {x!r}", f"v = {v!r}"]
    lines += ["[integrator]", 'method = "sesi2"', "dt = 0.01", "t_end = 8.0", "output_every = 20",
              f'trajectory_format = "{trajectory_format}"']
    return "\n".join(lines) + "\n", speeds2, radius


def csv_table(path):
    """Header and rows of a CSV file, cells as text (a surface's word is text)."""
    lines = pathlib.Path(path).read_text().splitlines()
    return lines[0].split(","), [line.split(",") for line in lines[1:]]


def run_scene(ctx, name, text):
    out = ctx.work / name
    expect_ok(ctx.run("run", ctx.write(f"{name}.toml", text), "--out", out, "-q"), f"sesi run {name}")
    return out


@case
def analyze_box_msd_and_largest_cutoff(ctx):
    text, speeds2 = free_box_scene()
    out = run_scene(ctx, "box", text)
    s = summary(out)
    check(s["space"].get("box") == [3, 4], f"summary.json space: {s['space']}")
    # The bodies crossed the faces: their image counts moved.
    header, rows = csv_table(out / "trajectory.csv")
    counts = [abs(int(r[header.index(f"b{b}_n{i}")])) for r in rows for b in (1, 2, 3) for i in (1, 2)]
    check(max(counts) >= 5, f"the bodies crossed few faces: largest image count {max(counts)}")
    result = ctx.run("analyze", out, "--no-picture", "--max-lag", "30")
    expect_ok(result, "sesi analyze of a box run")
    check("largest allowed cutoff 1.5" in result.stdout and "image counts" in result.stdout,
          f"report: {result.stdout!r}")
    # g(r) by default up to the largest allowed cutoff, half the shorter edge (ten mean spacings,
    # 10 sqrt(12 / 3) = 20, is farther).
    _, rdf = read_csv(out / "rdf.csv")
    check(rdf[-1][1] == 1.5, f"rdf.csv ends at {rdf[-1][1]}, expected the largest cutoff 1.5")
    # MSD: each body moves on a straight line at its speed, so MSD(t) = mean |v|^2 t^2. Bound: each
    # step's two half drifts and its reduction into the box round q to eps of |q| <= L + |v| dt
    # (3 roundings), so after S steps each unwrapped coordinate is within 3 S eps (L + |v| dt) of
    # the line, a displacement within 2 sqrt(2) times that, and d^2 within twice that over d
    # relative (d >= the least speed x the rows' spacing at lag 1).
    _, msd = read_csv(out / "msd.csv")
    steps, spacing = s["steps"], msd[1][1]
    delta = 2 * math.sqrt(2) * 3 * steps * EPS * (4.0 + 0.05 * math.sqrt(max(speeds2)))
    bound = 2 * delta / (math.sqrt(min(speeds2)) * spacing)
    mean2 = sum(speeds2) / len(speeds2)
    worst = max(abs(row[2] / (mean2 * row[1] ** 2) - 1) for row in msd[1:])
    check(worst < bound, f"MSD against mean |v|^2 t^2: relative error {worst:.3g}, bound {bound:.3g}")
    # A larger --rdf-max is refused with one line naming the largest, and nothing is written.
    before = snapshot(out)
    expect_input_error(ctx.run("analyze", out, "--rdf-max", "1.6"), key="--rdf-max",
                       text="the largest allowed cutoff is 1.5")
    expect_untouched(out, before)


@case
def analyze_surface_msd_and_vacf(ctx):
    text, speeds2, radius = free_surface_scene()
    out = run_scene(ctx, "surface", text)
    s = summary(out)
    check(s["space"].get("genus") == 2, f"summary.json space: {s['space']}")
    header, rows = csv_table(out / "trajectory.csv")
    words = [r[header.index(f"b{b}_word")] for r in rows for b in (1, 2, 3)]
    check(max(len(w.split(".")) for w in words if w != "e") >= 2, f"the bodies crossed few sides: {set(words)}")
    result = ctx.run("analyze", out, "--no-picture", "--max-lag", "20")
    expect_ok(result, "sesi analyze of a genus-2 run")
    check("words" in result.stdout, f"report: {result.stdout!r}")
    largest = s["space"]["max_cutoff"]
    _, rdf = read_csv(out / "rdf.csv")
    check(rdf[-1][1] == largest, f"rdf.csv ends at {rdf[-1][1]}, expected the largest cutoff {largest}")
    # Free bodies follow geodesics of H^2 at their speeds |v|_L (the unwrapped path is the free
    # geodesic: tests/core/topology.cpp): MSD(t) = mean |v|^2 t^2, VACF = mean |v|^2 at every lag.
    # Bound (the rounding tests/core/topology.cpp derives for free motion on a surface): each step
    # moves the chart coordinate by a rounded drift (2.1 eps R), and a wrap or re-basing (at most
    # one a step) replaces the frame by a rounded product, which moves the point by at most
    # (3 eps |gamma| |F| + 16 eps |F|^2) 5.3 R <= 20000 eps R (Frobenius norms: |F| <= 11.6 for a
    # boost by up to the circumradius, |gamma| <= 19 for a generator). After S steps the distance
    # is within 20000 S eps R of |v| t, d^2 within twice that over d relative. The VACF's
    # velocities carry the same relative error, and its Minkowski products of vectors of size
    # |v| cosh((d + r_c) / R) cancel down to |v|^2 (16 eps cosh^2((d + r_c) / R)), d <= |v| t.
    steps = s["steps"]
    delta = 20000 * steps * EPS * radius
    _, msd = read_csv(out / "msd.csv")
    mean2 = sum(speeds2) / len(speeds2)
    spacing = msd[1][1]
    bound = 2 * delta / (math.sqrt(min(speeds2)) * spacing)
    worst = max(abs(row[2] / (mean2 * row[1] ** 2) - 1) for row in msd[1:])
    check(worst < bound, f"MSD against mean |v|^2 t^2: relative error {worst:.3g}, bound {bound:.3g}")
    check(bound < 1e-3, "the bound must tell a wrong letter (an error of the systole's size)")
    _, vacf = read_csv(out / "vacf.csv")
    circumradius = radius * math.acosh(math.tan(math.pi / 8) ** -2)  # cosh r_c = cot^2(pi/8)
    for row in vacf[1:]:
        far = math.cosh((math.sqrt(max(speeds2)) * row[1] + circumradius) / radius)
        vbound = 20000 * steps * EPS + 16 * EPS * far * far
        check(abs(row[2] / mean2 - 1) < vbound, f"VACF at t = {row[1]}: {row[2]} against {mean2} (bound {vbound:.3g})")


@case
def analyze_topology_h5md_equals_csv(ctx):
    # The same doubles, image counts and words in both trajectories: the same observables, byte
    # for byte.
    for name, scene in [("box", free_box_scene), ("surface", free_surface_scene)]:
        csv_out = run_scene(ctx, f"{name}-csv", scene("csv")[0])
        h5_out = ctx.work / f"{name}-h5"
        result = ctx.run("run", ctx.write(f"{name}-h5.toml", scene("h5md")[0]), "--out", h5_out, "-q")
        if result.returncode == 2 and "HDF5" in result.stderr:
            return  # a program built without HDF5 refuses h5md (cases in outputs/ check that message)
        expect_ok(result, f"sesi run {name} with an H5MD trajectory")
        for out in (csv_out, h5_out):
            expect_ok(ctx.run("analyze", out, "--no-picture", "-q", "--max-lag", "10"), f"sesi analyze {out.name}")
        for file in ["rdf.csv", "msd.csv", "vacf.csv", "per_body.csv"]:
            check((csv_out / file).read_bytes() == (h5_out / file).read_bytes(), f"{name}: {file} differs")
