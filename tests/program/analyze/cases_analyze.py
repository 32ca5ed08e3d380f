# `sesi analyze DIR` (src/cli/analyze_command.cpp, src/analysis, docs/observables.md): the files it
# writes from CSV and H5MD trajectories, the manifest, bad input (one line, exit 2, nothing
# written), and the pictures. The numbers themselves are tested in test_analysis.cpp.

ANALYSIS_FILES = ["rdf.csv", "msd.csv", "vacf.csv", "per_body.csv"]


def lj_scene(bodies=40, t_end=1.0, output_every=10, trajectory_format="csv"):
    """A small Lennard-Jones gas on S^2: bodies on a Fibonacci spiral, fixed velocities."""
    radius = math.sqrt(bodies / (4 * math.pi * 0.3))
    golden = math.pi * (3 - math.sqrt(5))
    lines = ['name = "analyze-lj"', "[space]", 'kind = "sphere"', "dim = 2", f"radius = {radius!r}"]
    for k in range(bodies):
        z = 1 - 2 * (k + 0.5) / bodies
        rho = math.sqrt(1 - z * z)
        x = [radius * rho * math.cos(k * golden), radius * rho * math.sin(k * golden), radius * z]
        # a tangent velocity: along z x x, varied per body
        t = [-x[1], x[0], 0.0]
        norm = math.hypot(t[0], t[1]) or 1.0
        s = 0.5 + 0.5 * math.sin(k)
        v = [s * c / norm for c in t]
        lines += ["[[bodies]]", f"mass = {1.0 + (k % 3) * 0.5!r}", f"x = {x!r}", f"v = {v!r}"]
    lines += ["[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5",
              "[integrator]", 'method = "sesi2"', "dt = 0.005", f"t_end = {t_end!r}", f"output_every = {output_every}",
              f'trajectory_format = "{trajectory_format}"']
    return "\n".join(lines) + "\n"


def run_lj(ctx, out, **kwargs):
    scene = ctx.write(f"{pathlib.Path(out).name}.toml", lj_scene(**kwargs))
    expect_ok(ctx.run("run", scene, "--out", out, "-q"), "sesi run of the analysis scene")
    return scene


def expect_analysis(out):
    for name in ANALYSIS_FILES:
        check((out / name).is_file(), f"sesi analyze did not write {name}")
    manifest = (out / "sesi-manifest.txt").read_text().splitlines()
    for name in ANALYSIS_FILES:
        check(name in manifest, f"{name} is not in the manifest: {manifest}")
    header, rows = read_csv(out / "rdf.csv")
    check(header == ["r_lo", "r_hi", "r", "g", "count", "expected"], f"rdf.csv header {header}")
    check(len(rows) == 50, f"rdf.csv has {len(rows)} bins, expected 50 (--bins 50)")
    check(all(r[4] == int(r[4]) and r[4] >= 0 for r in rows), "rdf.csv counts are not whole numbers")
    check(sum(r[4] for r in rows) > 0, "rdf.csv counts no pair")
    header, rows = read_csv(out / "msd.csv")
    check(header == ["lag", "t", "msd", "samples"], f"msd.csv header {header}")
    check(rows[0][2] == 0.0 and rows[1][2] > 0.0, "msd.csv: lag 0 must be 0 and lag 1 positive")
    header, rows = read_csv(out / "vacf.csv")
    check(header == ["lag", "t", "vacf", "vacf_normalised", "samples"], f"vacf.csv header {header}")
    check(rows[0][3] == 1.0 and rows[0][2] > 0, "vacf.csv: lag 0 must be normalised to 1")
    header, rows = read_csv(out / "per_body.csv")
    check(header == ["body", "msd", "mean_speed2"] and len(rows) == 40, "per_body.csv: header or rows")


@case
def analyze_csv_run(ctx):
    out = ctx.work / "lj"
    scene = run_lj(ctx, out)
    result = ctx.run("analyze", out, "--bins", "50", "--no-picture")
    expect_ok(result, "sesi analyze")
    check("rdf.csv" in result.stdout and "saturates at" in result.stdout, f"report: {result.stdout!r}")
    expect_analysis(out)
    # The velocity autocorrelation at lag 0 is the mean of |v|^2 over frames and bodies: the
    # speeds written in summary.json's final state are a sample of it (same order of magnitude).
    _, vacf = read_csv(out / "vacf.csv")
    final = summary(out)["final_state"]["bodies"]
    mean_final = sum(sum(c * c for c in b["v"]) for b in final) / len(final)
    check(0.1 < vacf[0][2] / mean_final < 10, f"VACF(0) {vacf[0][2]} far from the final mean |v|^2 {mean_final}")
    # Again: the files sesi analyze wrote are its own now (the manifest), so it replaces them.
    expect_ok(ctx.run("analyze", out, "--bins", "50", "--no-picture", "-q"), "sesi analyze again")
    # A run repeated into the directory replaces the analysis like its other outputs.
    expect_ok(ctx.run("run", scene, "--out", out, "-q"), "sesi run into an analysed directory")
    for name in ANALYSIS_FILES:
        check(not (out / name).exists(), f"a rerun kept the earlier run's {name}")


@case
def analyze_h5md_equals_csv(ctx):
    csv_out, h5_out = ctx.work / "lj-csv", ctx.work / "lj-h5"
    run_lj(ctx, csv_out)
    scene = ctx.write("lj-h5.toml", lj_scene(trajectory_format="h5md"))
    result = ctx.run("run", scene, "--out", h5_out, "-q")
    if result.returncode == 2 and "HDF5" in result.stderr:
        return  # a program built without HDF5 refuses h5md (cases in outputs/ check that message)
    expect_ok(result, "sesi run with an H5MD trajectory")
    for out in (csv_out, h5_out):
        expect_ok(ctx.run("analyze", out, "--bins", "50", "--no-picture", "-q"), f"sesi analyze {out.name}")
    expect_analysis(h5_out)
    # The same doubles in both trajectories: the same observables, byte for byte.
    for name in ANALYSIS_FILES:
        check((csv_out / name).read_bytes() == (h5_out / name).read_bytes(), f"{name} differs between CSV and H5MD")


@case
def analyze_windows_and_lags(ctx):
    out = ctx.work / "lj"
    run_lj(ctx, out, t_end=1.0, output_every=10)  # 21 rows, t = 0, 0.05, ..., 1
    expect_ok(ctx.run("analyze", out, "--from", "0.5", "--every", "2", "--max-lag", "3", "--bins", "50",
                      "--no-picture", "-q"), "sesi analyze with a window")
    _, rows = read_csv(out / "msd.csv")
    # t in [0.5, 1]: 11 frames, every 2nd: 6 frames 0.1 apart; lags 0..3.
    check([r[0] for r in rows] == [0, 1, 2, 3], f"lags {[r[0] for r in rows]}")
    check(all(abs(r[1] - 0.1 * r[0]) < 1e-12 for r in rows), f"lag times {[r[1] for r in rows]}")
    check([r[3] for r in rows] == [6 * 40, 5 * 40, 4 * 40, 3 * 40], f"samples {[r[3] for r in rows]}")


@case
def analyze_bad_input(ctx):
    out = ctx.work / "lj"
    run_lj(ctx, out)
    before = snapshot(out)
    cases = [
        (["analyze", ctx.work / "missing"], "not a directory"),
        (["analyze", out, "--bins", "0"], "--bins"),
        (["analyze", out, "--rdf-max", "100"], "--rdf-max"),
        (["analyze", out, "--rdf-max", "-1"], "--rdf-max"),
        (["analyze", out, "--every", "0"], "--every"),
        (["analyze", out, "--max-lag", "-2"], "--max-lag"),
        (["analyze", out, "--from", "5"], "no frame"),
        (["analyze", out, "--from", "0.8", "--to", "0.2"], "--from"),
        (["analyze", out, "--from", "nan"], "--from"),
        (["analyze"], "DIR"),
    ]
    for args, text in cases:
        result = ctx.run(*args)
        expect_input_error(result, text=text)
        expect_untouched(out, before)
    # A directory that is not a finished run: no summary, and an unfinished (failed) run.
    empty = ctx.work / "empty"
    empty.mkdir()
    expect_input_error(ctx.run("analyze", empty), text="no summary.json")
    failed = ctx.work / "blowup"
    ctx.run("run", ctx.write("blowup.toml", BLOWUP), "--out", failed, "-q")
    check(not summary(failed)["complete"], "the blow-up scene should fail")
    before_failed = snapshot(failed)
    expect_input_error(ctx.run("analyze", failed), text="unfinished")
    expect_untouched(failed, before_failed)
    # A user's file of an analysis name is never overwritten.
    (out / "msd.csv").write_text("mine\n")
    before = snapshot(out)
    expect_input_error(ctx.run("analyze", out, "--no-picture"), text="msd.csv, which sesi did not write")
    expect_untouched(out, before)
    (out / "msd.csv").unlink()


@case
def analyze_pictures(ctx):
    out = ctx.work / "lj"
    run_lj(ctx, out)
    result = ctx.run("analyze", out, "-q")
    check(result.returncode == 0, f"exit status {result.returncode}: {result.stderr!r}")
    python = "/usr/bin/python3" if os.access("/usr/bin/python3", os.X_OK) else shutil.which("python3")
    has_matplotlib = python and subprocess.run([python, "-c", "import matplotlib"], capture_output=True).returncode == 0
    if has_matplotlib:
        check(result.stderr == "", f"unexpected stderr: {result.stderr!r}")
        for name in ["rdf.png", "msd.png"]:
            check((out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", f"{name} is not a PNG")
            check(name in (out / "sesi-manifest.txt").read_text().splitlines(), f"{name} not in the manifest")
    else:
        check("no pictures" in result.stderr and result.stderr.count("\n") == 1, f"stderr: {result.stderr!r}")
    check(not list(out.glob("*.tmp")), f"temporary files left: {list(out.glob('*.tmp'))}")


@case
def analyze_waits_for_no_run(ctx):
    # A run going into DIR holds its lock: sesi analyze refuses with one line rather than write
    # beside outputs that are about to be replaced.
    out = ctx.work / "lj"
    run_lj(ctx, out)
    before = snapshot(out)
    process = start_long_run(ctx, out, quiet=True)
    try:
        lock = ctx.work / ".lj.sesi-lock"
        for _ in range(600):  # the run takes the lock before it starts stepping
            if any(p.name.startswith(".lj.sesi-") and p.is_dir() for p in ctx.work.iterdir()):
                break
            time.sleep(0.01)
        check(lock.exists(), "the run into the directory took no lock")
        expect_input_error(ctx.run("analyze", out, "--no-picture"), text="in use by another sesi run")
        check(snapshot(out) == before, "sesi analyze changed the directory while a run held it")
    finally:
        process.send_signal(signal.SIGINT)
        process.communicate(timeout=60)


@case
def analyze_msd_reads_the_trajectory(ctx):
    # The MSD at lag 1 from sesi analyze against the geodesic distances of consecutive rows of
    # trajectory.csv computed here: H^2 (R acosh(-<x, y>_L / R^2)) and E^2 (|x - y|). Bound: the
    # acosh form loses about eps / (d/R)^2 relative (below 1e-10 for rows d > 0.002 R apart), the
    # library's polar form a few eps: 1e-9 relative is above both.
    for stem in ["hyperbolic-kepler-xv", "euclidean-figure-eight-qp"]:
        out = ctx.work / stem
        expect_ok(ctx.run("run", ctx.scene(f"{stem}.toml"), "--t-end", "2", "--out", out, "-q"), stem)
        expect_ok(ctx.run("analyze", out, "--max-lag", "1", "--no-picture", "-q"), f"sesi analyze {stem}")
        s = summary(out)
        header, rows = read_csv(out / "trajectory.csv")
        ambient = sum(1 for name in header if name.startswith("b1_x"))
        radius = s["space"].get("radius", 1.0)
        hyperbolic = s["space"]["kind"] == "hyperbolic"

        def distance(x, y):
            if hyperbolic:
                inner = sum(a * b for a, b in zip(x[:-1], y[:-1])) - x[-1] * y[-1]
                return radius * math.acosh(max(1.0, -inner / radius ** 2))
            return math.dist(x, y)

        columns = [[header.index(f"b{b + 1}_x{i + 1}") for i in range(ambient)] for b in range(s["bodies"])]
        # The rows on the even grid (a last row off it is left out by sesi analyze too).
        total, count = 0.0, 0
        for r0, r1 in zip(rows, rows[1:]):
            for cols in columns:
                total += distance([r0[c] for c in cols], [r1[c] for c in cols]) ** 2
                count += 1
        _, msd = read_csv(out / "msd.csv")
        check(msd[1][3] == count, f"{stem}: {msd[1][3]} samples at lag 1, expected {count}")
        check(abs(msd[1][2] / (total / count) - 1) < 1e-9, f"{stem}: MSD(1) {msd[1][2]} against {total / count}")
