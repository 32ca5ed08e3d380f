# method = "auto" (issue #15; docs/scheme.md, "Choosing a method: auto"): the method and step
# chosen for a target max relative energy error. Exec'd in check_program.py's namespace.

# The seed scene and two curved Kepler scenes, each at two tolerances: the run's max relative
# energy error lands within 10x of the tolerance (the pilot runs aim at 0.4x).
AUTO_SCENES = [("paper", [], "800"), ("sphere-kepler", ["sphere-kepler.toml"], "400"),
               ("hyperbolic-kepler-bound", ["hyperbolic-kepler-bound.toml"], "400")]


def auto_run(ctx, out, scene, t_end, tol, *extra):
    args = [ctx.scene(s) for s in scene]
    result = ctx.run("run", *args, "--tolerance", tol, "--t-end", t_end, "--out", out, "-q", *extra)
    expect_ok(result, f"auto run of {scene} at {tol}")
    return summary(out)


@case
def auto_meets_the_tolerance(ctx):
    names = set(ctx.run("run", "--list-methods").stdout.split())
    for name, scene, t_end in AUTO_SCENES:
        for tol in ("1e-6", "1e-9"):
            s = auto_run(ctx, ctx.work / f"{name}-{tol}", scene, t_end, tol)
            a, rel = s["auto"], s["energy"]["max_rel_error"]
            what = f"{name} at {tol}: {s['method']} dt {s['dt']}"
            check(s["method"] != "auto" and s["method"] in names, f"{what}: not a method of sesi run")
            check(float(tol) / 10 <= rel <= 10 * float(tol), f"{what}: max relative energy error {rel}")
            check(a["tolerance"] == float(tol) and a["reason"].startswith(s["method"]), f"{what}: {a}")
            check(abs(a["error_over_tolerance"] - rel / float(tol)) <= 1e-12 * rel / float(tol), f"{what}: {a}")
            picked = [c for c in a["candidates"] if c["method"] == s["method"]]
            check(len(picked) == 1 and picked[0]["second_pilot"] and s["dt"] <= picked[0]["dt"] * (1 + 1e-12),
                  f"{what}: the step is not the candidate's, at most: {picked}")
            check(all(c["predicted_cost"] is None or c["predicted_cost"] >= picked[0]["predicted_cost"]
                      for c in a["candidates"] if c["second_pilot"]),
                  f"{what}: a cheaper candidate was passed over: {a['candidates']}")
            if name == "paper":  # the default scene gives dt = 0.1: replaced, and the summary says so
                check(a["replaced_dt"] == 0.1, f"{what}: replaced_dt {a['replaced_dt']}")


@case
def auto_geodesic_candidates_only_on_curved_spaces(ctx):
    s = auto_run(ctx, ctx.work / "flat", ["euclidean-figure-eight-qp.toml"], "10", "1e-7")
    check(not s["method"].startswith("geodesic") and
          not any(c["method"].startswith("geodesic") for c in s["auto"]["candidates"]),
          f"a geodesic candidate on E^n: {s['auto']['candidates']}")
    check(s["energy"]["max_rel_error"] <= 1e-6, f"figure eight: {s['energy']}")


@case
def auto_is_deterministic(ctx):
    """The choice comes from runs of the scene, not from timings: any thread count, same outputs."""
    runs = []
    for threads in ("1", "2"):
        out = ctx.work / f"threads-{threads}"
        s = auto_run(ctx, out, ["sphere-kepler.toml"], "100", "1e-8", "--threads", threads)
        for key in ("wall_seconds", "threads_per_rank"):  # the run environment, not its results
            s.pop(key)
        s["auto"].pop("pilot_seconds")
        runs.append((s, (out / "trajectory.csv").read_bytes()))
    check(runs[0] == runs[1], "two auto runs differ")


@case
def auto_from_the_scene_file(ctx):
    """method = "auto" with tolerance in [integrator]; dt optional (rows every output_every steps)."""
    scene = ctx.write("auto.toml", (ctx.scene("sphere-kepler.toml").read_text()
                                    .replace('method = "sesi4"', 'method = "auto"\ntolerance = 1e-7')
                                    .replace("dt = 0.01\n", "")))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", scene, "--out", out, "-q"), "auto from the file")
    s = summary(out)
    check(s["auto"]["replaced_dt"] is None and s["output_every"] == 10, f"{s['auto']} {s['output_every']}")
    check(s["energy"]["max_rel_error"] <= 1e-6, f"{s['energy']}")
    # With a dt, the output interval (output_every x dt = 0.1) is kept to the nearest whole step.
    scene2 = ctx.write("auto-dt.toml", ctx.scene("sphere-kepler.toml").read_text()
                       .replace('method = "sesi4"', 'method = "auto"\ntolerance = 1e-7'))
    out2 = ctx.work / "out2"
    expect_ok(ctx.run("run", scene2, "--out", out2, "-q"), "auto with a dt")
    s2 = summary(out2)
    check(s2["auto"]["replaced_dt"] == 0.01 and s2["auto"]["replaced_output_every"] == 10, f"{s2['auto']}")
    check(s2["output_every"] == max(1, round(0.1 / s2["dt"])), f"output_every {s2['output_every']}, dt {s2['dt']}")


@case
def auto_resumed_keeps_its_choice(ctx):
    """A checkpoint holds the choice: the resumed run steps on with it, and its summary says why."""
    first = ctx.work / "first"
    s1 = auto_run(ctx, first, ["sphere-kepler.toml"], "40", "1e-8", "--checkpoint-every", "50")
    expect_ok(ctx.run("resume", first, "--t-end", "60", "--quiet"), "sesi resume")
    s2 = summary(first)
    check(s2["method"] == s1["method"] and s2["dt"] == s1["dt"] and s2["auto"] == s1["auto"] | {
        "error_over_tolerance": s2["auto"]["error_over_tolerance"]}, f"{s1['auto']} against {s2['auto']}")


@case
def auto_bad_settings(ctx):
    paper = ctx.scene("paper.toml")
    expect_input_error(ctx.run("run", "--method", "auto"), key="integrator.tolerance", text="needs a tolerance")
    expect_input_error(ctx.run("run", "--tolerance", "1e-6", "--method", "sesi4"), key="--tolerance",
                       text="only with --method auto")
    for bad in ("0", "1e-13", "0.5", "nan"):
        expect_input_error(ctx.run("run", "--tolerance", bad), key="--tolerance", text="from 1e-12 to 0.01")
    scene = ctx.write("tol.toml", paper.read_text().replace("[integrator]", "[integrator]\ntolerance = 1e-6"))
    expect_input_error(ctx.run("run", scene), key="integrator.tolerance", text="only with method")
    scene = ctx.write("auto-no-tol.toml", paper.read_text().replace('method = "sesi4"', 'method = "auto"'))
    expect_input_error(ctx.run("run", scene), key="integrator.tolerance", text="needs a tolerance")
    expect_input_error(ctx.run("run", "--method", "autoo"), key="--method", text="expected \"auto\" or")
