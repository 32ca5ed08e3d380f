# Bodies from a file (bodies = "FILE.csv", docs/scene-format.md "Bodies from a file"): the run is
# the same, byte for byte, as with the same bodies in [[bodies]] tables, the path resolved against
# the scene file's directory (not the current one); a bad row is refused like a bad table (exit 2,
# one line naming the file, the line and the key, nothing written). The reader's own cases are in
# test_scene_csv.cpp. Exec'd in check_program.py's namespace (names prefixed bodies_file_).

BODIES_FILE_SCENE = """name = "bodies-file"
[space]
kind = "sphere"
dim = 2
[[potential]]
kind = "cotangent-gravity"
[integrator]
method = "sesi4"
dt = 0.01
t_end = 0.5
output_every = 10
"""

# (mass, x, v) on the unit sphere; x on it and v tangent exactly in decimal (3-4-5 triangles).
BODIES_FILE_BODIES = [
    (1.0, (0.6, 0.0, 0.8), (0.0, 0.5, 0.0)),
    (0.5, (0.0, -0.8, 0.6), (0.3, 0.0, 0.0)),
    (2.0, (-0.8, 0.6, 0.0), (0.0, 0.0, 0.25)),
]


def bodies_file_csv(bodies):
    rows = ["# mass, then the embedding point and velocity", "v1, v2, v3, mass, x1, x2, x3"]
    rows += [",".join(repr(c) for c in (*v, m, *x)) for m, x, v in bodies]
    return "\n".join(rows) + "\n"


@case
def bodies_file_same_run_as_tables(ctx):
    tables = "".join(f"[[bodies]]\nmass = {m!r}\nx = {list(x)}\nv = {list(v)}\n" for m, x, v in BODIES_FILE_BODIES)
    expect_ok(ctx.run("run", ctx.write("tables.toml", BODIES_FILE_SCENE + tables), "--out", ctx.work / "tables", "-q"),
              "[[bodies]] tables")
    # The scene in a directory of its own, run from its parent: the file is found beside the scene.
    (ctx.work / "scene").mkdir(exist_ok=True)
    ctx.write("scene/bodies.csv", bodies_file_csv(BODIES_FILE_BODIES))
    scene = ctx.write("scene/file.toml", 'bodies = "bodies.csv"\n' + BODIES_FILE_SCENE)
    expect_ok(ctx.run("run", scene, "--out", ctx.work / "file", "-q"), "bodies = \"bodies.csv\"")
    a = (ctx.work / "tables" / "trajectory.csv").read_bytes()
    b = (ctx.work / "file" / "trajectory.csv").read_bytes()
    check(len(a.splitlines()) == 7, f"expected a header and 6 rows (t = 0, 0.1, ..., 0.5), got {len(a.splitlines())} lines")
    check(a == b, "trajectory.csv differs between [[bodies]] tables and the bodies file")


@case
def bodies_file_bad_row(ctx):
    # The third body moved off the sphere (|x| = 1.0001): refused at its line (5: a comment, the header, two rows).
    bodies = BODIES_FILE_BODIES[:2] + [(2.0, (-0.8, 0.6001, 0.0), (0.0, 0.0, 0.25))]
    csv = ctx.write("bad.csv", bodies_file_csv(bodies))
    scene = ctx.write("bad.toml", 'bodies = "bad.csv"\n' + BODIES_FILE_SCENE)
    out = ctx.work / "out"
    before = earlier_outputs(out)
    result = ctx.run("run", scene, "--out", out)
    expect_input_error(result, file=csv, line=5, key="bodies[3].x", text="not on the sphere")
    expect_untouched(out, before)


@case
def bodies_file_in_a_sweep(ctx):
    # Each run of a sweep reads its scene in its own directory: the bodies file, relative to the
    # base scene, must still be found (the runs name it by its absolute path).
    (ctx.work / "base").mkdir(exist_ok=True)
    ctx.write("base/bodies.csv", bodies_file_csv(BODIES_FILE_BODIES))
    ctx.write("base/scene.toml", 'bodies = "bodies.csv"\n' + BODIES_FILE_SCENE)
    sweep = ctx.write("base/sweep.toml", 'scene = "scene.toml"\n[[vary]]\nkey = "integrator.dt"\nvalues = [0.01, 0.02]\n')
    expect_ok(ctx.run("sweep", sweep, "--out", ctx.work / "sweep"), "sesi sweep")
    for run in ["0", "1"]:
        scene = (ctx.work / "sweep" / "runs" / f"000{run}" / "scene.toml").read_text()
        check(f"bodies = '{(ctx.work / 'base' / 'bodies.csv').absolute()}'" in scene,
              f"run {run}'s scene does not name the bodies file by its absolute path: {scene!r}")
