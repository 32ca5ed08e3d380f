# The topology keys of [space] (issue #26; docs/scene-format.md): box on E^n, genus on H^2. Every
# bad combination is refused with one line naming the key and its line and the allowed value,
# exit status 2, nothing written. Exec'd in check_program.py's namespace (names prefixed topology_scene_).

TOPOLOGY_SCENE_BOX = """[space]
kind = "euclidean"
dim = 2
box = [6.0, 6.0]

[[bodies]]
mass = 1.0
x = [1.0, 1.0]
v = [0.5, 0.2]

[[bodies]]
mass = 1.0
x = [2.2, 1.0]
v = [-0.5, 0.1]
"""

TOPOLOGY_SCENE_SURFACE = """[space]
kind = "hyperbolic"
dim = 2
radius = 3.0
genus = 2

[[bodies]]
mass = 1.0
q = [0.5, 0.0]
p = [0.0, 0.3]

[[bodies]]
mass = 1.0
q = [0.5, 3.0]
p = [0.1, 0.0]
"""

TOPOLOGY_SCENE_LJ = '\n[[potential]]\nkind = "lennard-jones"\ncutoff = 2.5\n'
TOPOLOGY_SCENE_RUN = '\n[integrator]\ndt = 0.01\nt_end = 0.1\n'


def topology_scene_space(table, body="x = [1.0, 1.0]"):
    """A scene whose [space] is `table`, with one body and a short run."""
    return (table + "\n[[bodies]]\nmass = 1.0\n" + body + "\n" + TOPOLOGY_SCENE_RUN)


# (name, scene text, key, marker of the line sesi must name, text in the message)
TOPOLOGY_SCENE_BAD = [
    ("box on a sphere", topology_scene_space('[space]\nkind = "sphere"\ndim = 2\nbox = [5.0, 5.0]\n', "q = [1.0, 0.0]"),
     "space.box", "box =", "a periodic box is for a euclidean space"),
    ("box on hyperbolic", topology_scene_space('[space]\nkind = "hyperbolic"\ndim = 2\nbox = [5.0, 5.0]\n', "q = [1.0, 0.0]"),
     "space.box", "box =", "give genus"),
    ("box too short", topology_scene_space('[space]\nkind = "euclidean"\ndim = 2\nbox = [5.0]\n'),
     "space.box", "box =", "expected an array of 2 numbers"),
    ("box too long", topology_scene_space('[space]\nkind = "euclidean"\ndim = 2\nbox = [5.0, 5.0, 5.0]\n'),
     "space.box", "box =", "got 3 numbers"),
    ("box not an array", topology_scene_space('[space]\nkind = "euclidean"\ndim = 2\nbox = 5.0\n'),
     "space.box", "box =", "expected an array of 2 numbers"),
    ("box edge zero", topology_scene_space('[space]\nkind = "euclidean"\ndim = 2\nbox = [5.0, 0.0]\n'),
     "space.box[2]", "box =", "expected a finite edge > 0, got 0"),
    ("box edge negative", topology_scene_space('[space]\nkind = "euclidean"\ndim = 2\nbox = [-5.0, 5.0]\n'),
     "space.box[1]", "box =", "expected a finite edge > 0, got -5"),
    ("box edge infinite", topology_scene_space('[space]\nkind = "euclidean"\ndim = 2\nbox = [inf, 5.0]\n'),
     "space.box[1]", "box =", "finite"),
    ("box edge nan", topology_scene_space('[space]\nkind = "euclidean"\ndim = 2\nbox = [5.0, nan]\n'),
     "space.box[2]", "box =", "finite"),
    ("genus on euclidean", topology_scene_space('[space]\nkind = "euclidean"\ndim = 2\ngenus = 2\n'),
     "space.genus", "genus =", "is for a hyperbolic space"),
    ("genus on a sphere", topology_scene_space('[space]\nkind = "sphere"\ndim = 2\ngenus = 2\n', "q = [1.0, 0.0]"),
     "space.genus", "genus =", "is for a hyperbolic space"),
    ("genus in dim 3", topology_scene_space('[space]\nkind = "hyperbolic"\ndim = 3\ngenus = 2\n', "q = [1.0, 1.0, 0.0]"),
     "space.genus", "genus =", "expected dim = 2, got dim = 3"),
    ("genus one", topology_scene_space('[space]\nkind = "hyperbolic"\ndim = 2\ngenus = 1\n', "q = [1.0, 0.0]"),
     "space.genus", "genus =", "expected an integer from 2 to"),
    ("genus zero", topology_scene_space('[space]\nkind = "hyperbolic"\ndim = 2\ngenus = 0\n', "q = [1.0, 0.0]"),
     "space.genus", "genus =", "expected an integer from 2 to"),
    ("genus too large", topology_scene_space('[space]\nkind = "hyperbolic"\ndim = 2\ngenus = 100000\n', "q = [1.0, 0.0]"),
     "space.genus", "genus =", "expected an integer from 2 to"),
    ("genus a float", topology_scene_space('[space]\nkind = "hyperbolic"\ndim = 2\ngenus = 2.5\n', "q = [1.0, 0.0]"),
     "space.genus", "genus =", "got a float"),
    ("box cutoff past half the shortest edge",
     TOPOLOGY_SCENE_BOX.replace("box = [6.0, 6.0]", "box = [4.5, 6.0]") + TOPOLOGY_SCENE_LJ + TOPOLOGY_SCENE_RUN,
     "potential[1].cutoff", "cutoff = 2.5", "the largest allowed cutoff is 2.25"),
    ("box default cutoff past half the shortest edge",
     TOPOLOGY_SCENE_BOX.replace("box = [6.0, 6.0]", "box = [6.0, 4.0]") + '\n[[potential]]\nkind = "lennard-jones"\n'
     + TOPOLOGY_SCENE_RUN, "potential[1].cutoff", '[[potential]]', "the largest allowed cutoff is 2"),
    ("surface cutoff past the largest", TOPOLOGY_SCENE_SURFACE.replace("radius = 3.0", "radius = 1.0")
     + TOPOLOGY_SCENE_LJ + TOPOLOGY_SCENE_RUN, "potential[1].cutoff", "cutoff = 2.5", "the largest allowed cutoff is"),
    ("harmonic pair in a box", TOPOLOGY_SCENE_BOX + '\n[[potential]]\nkind = "harmonic-pair"\nk = 1.0\n' + TOPOLOGY_SCENE_RUN,
     "potential[1].kind", 'kind = "harmonic-pair"', "has no cutoff"),
    ("gravity on a surface", TOPOLOGY_SCENE_SURFACE + '\n[[potential]]\nkind = "cotangent-gravity"\n' + TOPOLOGY_SCENE_RUN,
     "potential[1].kind", 'kind = "cotangent-gravity"', "only short-range pair terms"),
    ("central term in a box", TOPOLOGY_SCENE_BOX + '\n[[potential]]\nkind = "central-cotangent"\ncenter = [3.0, 3.0]\n'
     + TOPOLOGY_SCENE_RUN, "potential[1].kind", 'kind = "central-cotangent"', "external term"),
    ("processed method in a box", TOPOLOGY_SCENE_BOX + TOPOLOGY_SCENE_LJ
     + '\n[integrator]\nmethod = "sesi6-processed"\ndt = 0.01\nt_end = 0.1\n',
     "integrator.method", 'method = "sesi6-processed"', "must be a chart composition that is not processed"),
    ("geodesic method on a surface", TOPOLOGY_SCENE_SURFACE + '\n[integrator]\nmethod = "geodesic4"\ndt = 0.01\nt_end = 0.1\n',
     "integrator.method", 'method = "geodesic4"', "sesi8-kahan-li"),
]


@case
def topology_scene_bad_values(ctx):
    """Each bad topology: exit 2, one line naming the file, the line and the key, nothing written."""
    out = ctx.work / "out"
    before = earlier_outputs(out)
    for name, text, key, marker, message in TOPOLOGY_SCENE_BAD:
        path = ctx.write("bad-topology.toml", text)
        line = next(n for n, l in enumerate(text.splitlines(), start=1) if marker in l)
        result = ctx.run("run", path, "--out", out)
        try:
            expect_input_error(result, file=path, line=line, key=key, text=message)
        except Failure as e:
            raise Failure(f"{name}: {e}")
        expect_untouched(out, before)


@case
def topology_scene_method_option_refused(ctx):
    """A method from the command line that cannot run on a topology is refused like one in the file."""
    out = ctx.work / "out"
    before = earlier_outputs(out)
    path = ctx.write("box.toml", TOPOLOGY_SCENE_BOX + TOPOLOGY_SCENE_LJ + TOPOLOGY_SCENE_RUN)
    for method in ("sesi8-processed", "geodesic6"):
        result = ctx.run("run", path, "--method", method, "--out", out)
        expect_input_error(result, key="--method", text="must be a chart composition that is not processed")
        check(method in result.stderr, f"--method {method}: the message does not name it: {result.stderr!r}")
        expect_untouched(out, before)


@case
def topology_scene_good_keys(ctx):
    """A box and a genus that are allowed run, and summary.json keeps the space's kind and dimension."""
    for name, text in (("box", TOPOLOGY_SCENE_BOX + TOPOLOGY_SCENE_LJ + TOPOLOGY_SCENE_RUN),
                       ("surface", TOPOLOGY_SCENE_SURFACE + TOPOLOGY_SCENE_LJ.replace("2.5", "1.5") + TOPOLOGY_SCENE_RUN),
                       ("box-3d", '[space]\nkind = "euclidean"\ndim = 3\nbox = [4.0, 5.0, 6.0]\n'
                        '[[bodies]]\nmass = 1.0\nx = [1.0, 1.0, 1.0]\nv = [0.3, 0.0, -0.2]\n'
                        '[[bodies]]\nmass = 1.0\nx = [2.2, 1.0, 5.9]\nv = [-0.3, 0.0, 0.2]\n'
                        + TOPOLOGY_SCENE_LJ.replace("2.5", "2.0") + TOPOLOGY_SCENE_RUN),
                       ("box-5d", '[space]\nkind = "euclidean"\ndim = 5\nbox = [6.0, 6.0, 6.0, 6.0, 6.0]\n'
                        '[[bodies]]\nmass = 1.0\nx = [1.0, 1.0, 1.0, 1.0, 1.0]\nv = [0.3, 0.0, -0.2, 0.0, 0.1]\n'
                        '[[bodies]]\nmass = 1.0\nx = [2.2, 1.0, 1.0, 1.0, 1.0]\nv = [-0.3, 0.0, 0.2, 0.0, 0.0]\n'
                        + TOPOLOGY_SCENE_LJ + TOPOLOGY_SCENE_RUN)):
        path = ctx.write(f"{name}.toml", text)
        out = ctx.work / name
        expect_ok(ctx.run("run", path, "--out", out, "--quiet"), name)
        s = summary(out)
        check(s["complete"] is True, f"{name}: the run is not complete")


@case
def topology_scene_same_point_through_an_image(ctx):
    """Two bodies at the same point of the quotient, given as different points of the cover (a box
    edge apart; a generator of the genus-2 group apart), are refused like two bodies at one point:
    the scene checks measure the minimum image."""
    out = ctx.work / "out"
    before = earlier_outputs(out)
    box = TOPOLOGY_SCENE_BOX.replace("x = [2.2, 1.0]", "x = [7.0, -5.0]") + TOPOLOGY_SCENE_LJ + TOPOLOGY_SCENE_RUN
    # The generator of side 0 (Sausset & Tarjus 2007): the boost along the side's direction (angle 0)
    # by twice the inradius, cosh(inradius) = cot(pi/8); it maps the first body to a point of the
    # neighbouring tile, the same point of the surface.
    radius, rapidity = 3.0, 2.0 * math.acosh(1.0 / math.tan(math.pi / 8.0))
    x = [radius * math.sinh(0.5), 0.0, radius * math.cosh(0.5)]
    y = [math.cosh(rapidity) * x[0] + math.sinh(rapidity) * x[2], 0.0,
         math.sinh(rapidity) * x[0] + math.cosh(rapidity) * x[2]]
    surface = ('[space]\nkind = "hyperbolic"\ndim = 2\nradius = 3.0\ngenus = 2\n'
               f"[[bodies]]\nmass = 1.0\nx = [{x[0]!r}, 0.0, {x[2]!r}]\n"
               f"[[bodies]]\nmass = 1.0\nx = [{y[0]!r}, 0.0, {y[2]!r}]\n" + TOPOLOGY_SCENE_LJ + TOPOLOGY_SCENE_RUN)
    for name, text, marker in (("box", box, "x = [7.0, -5.0]"), ("surface", surface, f"x = [{y[0]!r}")):
        path = ctx.write(f"same-{name}.toml", text)
        # (A body's error points at its [[bodies]] table.)
        lines = text.splitlines()
        at = next(n for n, l in enumerate(lines) if marker in l)
        line = max(n for n in range(at) if lines[n] == "[[bodies]]") + 1
        result = ctx.run("run", path, "--out", out)
        try:
            expect_input_error(result, file=path, line=line, key="bodies[2].x", text="bodies[1]")
        except Failure as e:
            raise Failure(f"{name}: {e}")
        expect_untouched(out, before)


@case
def topology_scene_bench_refused(ctx):
    """sesi bench's work-precision sweep (every method, on the whole H^n) refuses a scene on a
    compact surface with one line, writing nothing."""
    path = ctx.write("surface.toml", TOPOLOGY_SCENE_SURFACE + TOPOLOGY_SCENE_LJ.replace("2.5", "1.5") + TOPOLOGY_SCENE_RUN)
    out = ctx.work / "bench"
    result = ctx.run("bench", "--scene", path, "--out", out)
    expect_input_error(result, text="scene files without a topology only")
    check(not out.exists(), "sesi bench wrote its output directory")
