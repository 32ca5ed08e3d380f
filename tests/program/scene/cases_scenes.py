# Reading scenes (src/scene): bad scenes, one case each; one state given two ways; dimensions
# 1 to 10; non-ASCII strings; the example scenes, one case each. The reader's limits are in
# cases_reader_limits.py.
# Exec'd in check_program.py's namespace: case, case_family, check, expect_input_error, ... come
# from there.


# ---- bad scenes (scene/bad/*.toml) -------------------------------------------------------------

BAD_SCENES = HERE / "scene" / "bad"


def bad_scene_expectations(path):
    expect = {"key": "", "text": "", "line": 0}
    for line in path.read_text().splitlines():
        if line.startswith("# expect-"):
            name, _, value = line[len("# expect-"):].partition(":")
            expect[name] = value.strip()
    expect["line"] = int(expect["line"] or 0)
    return expect


def run_bad_scene(ctx, stem):
    path = BAD_SCENES / f"{stem}.toml"
    expect = bad_scene_expectations(path)
    out = ctx.work / "out"
    before = earlier_outputs(out)
    result = ctx.run("run", path, "--out", out)
    expect_input_error(result, file=path, line=expect["line"], key=expect["key"], text=expect["text"])
    expect_untouched(out, before)


def bad_scene_stems(source):
    return [p.stem for p in sorted(BAD_SCENES.glob("*.toml"))]


case_family("bad_", bad_scene_stems, run_bad_scene)


# ---- scenes given two ways, dimensions ---------------------------------------------------------

def same_trajectories(a, b, tolerance):
    ha, ra = read_csv(a)
    hb, rb = read_csv(b)
    check(ha == hb and len(ra) == len(rb), "different headers or row counts")
    worst = max(abs(x - y) / (1 + abs(x)) for r, s in zip(ra, rb) for x, y in zip(r, s))
    check(worst <= tolerance, f"trajectories differ by {worst:.3g} > {tolerance:.3g}")


def qp_equals_xv(ctx, name):
    # The files give one state two ways; the conversion x, v -> q, p is exact to round-off, which
    # the dynamics amplify only slowly over t = 1.
    for form in ["qp", "xv"]:
        expect_ok(ctx.run("run", ctx.scene(f"{name}-{form}.toml"), "--t-end", "1", "--out", ctx.work / form, "-q"),
                  form)
    same_trajectories(ctx.work / "qp" / "trajectory.csv", ctx.work / "xv" / "trajectory.csv", 1e-12)


@case
def qp_equals_xv_sphere(ctx):
    qp_equals_xv(ctx, "sphere-two-body")


@case
def qp_equals_xv_hyperbolic(ctx):
    qp_equals_xv(ctx, "hyperbolic-kepler")


@case
def qp_equals_xv_euclidean(ctx):
    qp_equals_xv(ctx, "euclidean-figure-eight")


def embedded_scene(kind, dim, bodies, potentials, t_end):
    lines = [f'name = "{kind}{dim}"', "[space]", f'kind = "{kind}"', f"dim = {dim}"]
    for x, v in bodies:
        lines += ["[[bodies]]", "mass = 1.0", f"x = {list(x)}", f"v = {list(v)}"]
    lines += potentials
    lines += ["[integrator]", 'method = "sesi4"', "dt = 0.01", f"t_end = {t_end}"]
    return "\n".join(lines) + "\n"


def dimensions(ctx, kind, bodies2, potentials, lift):
    """The same motion on a totally geodesic 2-dimensional subspace of spaces of dimension 2..10
    (fixed-size charts up to 4, Eigen::Dynamic above): the embedding points must agree with the
    2-dimensional run to round-off (amplified over t = 1). Dimension 1 must run."""
    ambient2 = len(bodies2[0][0])
    runs = {}
    for dim in range(2, 11):
        bodies = [(lift(x, dim), lift(v, dim)) for x, v in bodies2]
        path = ctx.write(f"{kind}{dim}.toml", embedded_scene(kind, dim, bodies, [p(dim) for p in potentials], 1.0))
        out = ctx.work / f"out{dim}"
        expect_ok(ctx.run("run", path, "--out", out, "-q"), f"{kind} dim {dim}")
        header, rows = read_csv(out / "trajectory.csv")
        runs[dim] = (header, rows)
    reference = runs[2][1]
    for dim in range(3, 11):
        header, rows = runs[dim]
        check(len(rows) == len(reference), f"dim {dim}: {len(rows)} rows")
        for b in range(len(bodies2)):
            ref_cols = [runs[2][0].index(f"b{b + 1}_x{a + 1}") for a in range(ambient2)]
            cols = [header.index(f"b{b + 1}_x{a + 1}") for a in lift_index(kind, dim)]
            worst = max(abs(r[c] - s[k]) for r, s in zip(rows, reference) for c, k in zip(cols, ref_cols))
            check(worst < 1e-12, f"{kind} dim {dim}, body {b + 1}: x differs from dim 2 by {worst:.3g}")
    # Dimension 1: the circle, the hyperbolic line, the line.
    one = {"sphere": [([1.0, 0.0], [0.0, 0.5]), ([0.0, 1.0], [-0.3, 0.0])],
           "hyperbolic": [([3.626860407847019, 3.7621956910836314], [1.1286587073250893, 1.0880581223541057]),
                          ([-1.1752011936438014, 1.5430806348152437], [0.0, 0.0])],
           "euclidean": [([0.0], [0.5]), ([1.5], [0.0])]}[kind]
    path = ctx.write(f"{kind}1.toml", embedded_scene(kind, 1, one, [p(1) for p in potentials], 1.0))
    expect_ok(ctx.run("run", path, "--out", ctx.work / "out1", "-q"), f"{kind} dim 1")


def lift_index(kind, dim):
    """Where the coordinates of the 2-dimensional subspace sit in dimension dim."""
    if kind == "hyperbolic":
        return [0, 1, dim]  # (x1, x2, 0, ..., 0, x_time)
    return list(range(3 if kind == "sphere" else 2))


def lifter(kind):
    def lift(x, dim):
        x = list(x)
        if kind == "sphere":
            return x + [0.0] * (dim - 2)
        if kind == "hyperbolic":
            return x[:2] + [0.0] * (dim - 2) + [x[2]]
        return x + [0.0] * (dim - 2)
    return lift


@case
def dimensions_sphere(ctx):
    bodies = [([0.9320390859672263, 0.0, 0.3623577544766736], [0.0, 0.4291665510839589, 0.0]),
              ([0.9463000876874145, 0.0, -0.32328956686350335], [0.0, -0.4226988935164609, 0.0])]
    potentials = [lambda dim: '[[potential]]\nkind = "cotangent-gravity"\nG = 1.0']
    dimensions(ctx, "sphere", bodies, potentials, lifter("sphere"))


@case
def dimensions_hyperbolic(ctx):
    bodies = [([0.888105982187623, 0.0, 1.3374349463048447], [0.0, 0.6755950438730891, 0.0]),
              ([-1.5256189899643362, 1.1396714025940833, 2.1508984653931407],
               [-0.8474738575766381, -0.41567277560476557, 0.3808603002903068])]
    potentials = [lambda dim: '[[potential]]\nkind = "central-cotangent"\ncenter = '
                  + str([0.0] * dim + [1.0]),
                  lambda dim: '[[potential]]\nkind = "cotangent-gravity"\nG = 0.1']
    dimensions(ctx, "hyperbolic", bodies, potentials, lifter("hyperbolic"))


@case
def dimensions_euclidean(ctx):
    bodies = [([0.97000436, -0.24308753], [0.466203685, 0.43236573]),
              ([-0.97000436, 0.24308753], [0.466203685, 0.43236573]),
              ([0.0, 0.0], [-0.93240737, -0.86473146])]
    potentials = [lambda dim: '[[potential]]\nkind = "cotangent-gravity"\nG = 1.0',
                  lambda dim: '[[potential]]\nkind = "harmonic-pair"\nk = 0.1\nd0 = 1.0']
    dimensions(ctx, "euclidean", bodies, potentials, lifter("euclidean"))


@case
def non_ascii_strings_read_back(ctx):
    # The reader shields toml++ 3.3 from code points it mishandles (U+00A1..U+0499 and others,
    # src/scene/scene_reader.cpp); inside strings and comments they must read back unchanged.
    name = "caf\u00e9-\u0416-\u30a2\u30fc-\ufb30"
    text = (ctx.source / "examples" / "scenes" / "paper.toml").read_text()
    text = f'# Scene \u2014 with \u00e9 and \u3001 in a comment\nname = "{name}"\n' + \
        "\n".join(line for line in text.splitlines() if not line.startswith("name"))
    path = ctx.work / "accents.toml"
    path.write_text(text + "\n", encoding="utf-8")
    result = ctx.run("run", path, "--t-end", "1", cwd=ctx.work)
    expect_ok(result, "scene with non-ASCII strings")
    check(result.stdout.startswith(name + ":"), f"name not read back: {result.stdout[:80]!r}")
    check((ctx.work / "sesi-out" / name / "summary.json").is_file(), "output directory not named after the scene")


# ---- the example scenes -----------------------------------------------------------------------

def run_example(ctx, stem):
    path = ctx.scene(f"{stem}.toml")
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--t-end", "0.5", "--out", out, "-q"), stem)
    s = summary(out)
    check(s["complete"] and s["steps"] > 0, f"{stem}: {s['stop_reason']}")
    check(abs(s["energy"]["max_rel_error"]) < 1e-3, f"{stem}: relative energy error {s['energy']['max_rel_error']}")


@case
def example_scenes_cover_spaces(ctx):
    stems = {p.stem for p in (ctx.source / "examples" / "scenes").glob("*.toml")}
    check("paper" in stems, "examples/scenes/paper.toml missing")
    for kind in ["sphere", "hyperbolic", "euclidean"]:
        for form in ["qp", "xv"]:
            found = [s for s in stems if s.startswith(kind) and s.endswith(f"-{form}")]
            check(found, f"no {kind} example with {form} initial conditions")


def example_stems(source):
    return [p.stem for p in sorted((pathlib.Path(source) / "examples" / "scenes").glob("*.toml"))]


case_family("example_", example_stems, run_example)
