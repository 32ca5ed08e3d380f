# The run loop (src/run): reproducible numbers, the time grid, runs that fail, the energy guard
# and the close-encounter floor. Checkpoints, resume and signals are in cases_checkpoint.py (which
# uses harmonic_scene and expect_run_failure from here); runs far from the chart origin are in
# cases_far.py. Exec'd in check_program.py's namespace: case, check, BLOWUP, expect_ok, summary,
# ... come from there.


@case
def reproducible(ctx):
    # -ffp-contract=off and no -ffast-math: the same scene gives bit-identical numbers on one machine.
    for scene in ["paper.toml", "sphere-pole-crossing.toml", "hyperbolic-kepler-xv.toml"]:
        runs = []
        for k in range(2):
            out = ctx.work / f"repro-{scene}-{k}"
            expect_ok(ctx.run("run", ctx.scene(scene), "--t-end", "20", "--quiet", "--out", out), scene)
            data = summary(out)
            data.pop("wall_seconds")
            runs.append((data, (out / "trajectory.csv").read_bytes(), (out / "diagnostics.csv").read_bytes()))
        check(runs[0] == runs[1], f"two runs of {scene} differ")


# ---- the time grid -----------------------------------------------------------------------------

@case
def output_every(ctx):
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "10", "--output-every", "7", "--out", out, "-q"), "run")
    _, rows = read_csv(out / "trajectory.csv")
    times = [r[0] for r in rows]
    expected = [k * 0.1 for k in range(0, 100, 7)] + [10.0]
    check(len(times) == len(expected) and all(abs(a - b) < 1e-12 for a, b in zip(times, expected)),
          f"row times {times}")
    _, drows = read_csv(out / "diagnostics.csv")
    check([r[0] for r in drows] == times, "diagnostics rows differ from trajectory rows")


@case
def partial_last_step(ctx):
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--dt", "0.3", "--t-end", "1", "--out", out, "-q"), "run")
    s = summary(out)
    _, rows = read_csv(out / "trajectory.csv")
    check(s["steps"] == 4 and s["final_state"]["t"] == 1.0, f"steps {s['steps']}, final t {s['final_state']['t']}")
    check([r[0] for r in rows] == [0.0, 0.3, 0.6, 0.8999999999999999, 1.0] or
          all(abs(a - b) < 1e-15 for a, b in zip([r[0] for r in rows], [0, 0.3, 0.6, 0.9, 1.0])),
          f"row times {[r[0] for r in rows]}")


@case
def t_end_zero(ctx):
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "0", "--out", out, "-q"), "run")
    s = summary(out)
    _, rows = read_csv(out / "trajectory.csv")
    check(s["steps"] == 0 and s["complete"] and len(rows) == 1, "a zero-length run has the initial row only")


@case
def backward_run_returns(ctx):
    """A negative dt runs backwards; the methods are time-reversible, so running the paper scene
    forward to t = 5 and back from its final state returns to the initial state up to the
    round-off of 100 steps."""
    out = ctx.work / "forward"
    expect_ok(ctx.run("run", "--t-end", "5", "--out", out, "-q"), "forward")
    final = summary(out)["final_state"]["bodies"]
    text = ["[space]", 'kind = "sphere"', "dim = 2"]
    for b in final:
        text += ["[[bodies]]", "mass = 1.0", f"q = {b['q']}", f"p = {b['p']}"]
    text += ["[[potential]]", 'kind = "chord-well"', "theta0 = 0.7853981633974483",
             "[integrator]", "dt = -0.1", "t_end = 5"]
    path = ctx.write("back.toml", "\n".join(text) + "\n")
    back = ctx.work / "back"
    expect_ok(ctx.run("run", path, "--out", back, "-q"), "backward")
    s = summary(back)
    check(s["final_state"]["t"] == -5.0, f"final t {s['final_state']['t']}")
    _, rows = read_csv(out / "trajectory.csv")
    start = rows[0]
    for b, body in enumerate(s["final_state"]["bodies"]):
        q0 = start[1 + 7 * b: 3 + 7 * b]
        p0 = start[3 + 7 * b: 5 + 7 * b]
        worst = max(abs(a - c) for a, c in zip(body["q"] + body["p"], q0 + p0))
        check(worst < 1e-12, f"body {b + 1} returns to within {worst:.3g}")


# ---- runs that fail ----------------------------------------------------------------------------

@case
def non_finite_run(ctx):
    path = ctx.write("blowup.toml", BLOWUP)
    out = ctx.work / "out"
    earlier_outputs(out)
    result = ctx.run("run", path, "--out", out)
    err = result.stderr
    check(result.returncode == 3, f"exit status {result.returncode}, expected 3: {err!r}")
    check(err.count("\n") == 1 and err.startswith("sesi: error: "), f"expected one line: {err!r}")
    s = summary(out)
    failure = s["failure"]
    check(s["complete"] is False and s["stop_reason"] == "non-finite state", f"summary {s}")
    check(f"step {failure['step']} " in err and f"t = {failure['t']:g}" in err and f"body {failure['body']}" in err,
          f"stderr does not name step, time and body: {err!r}")
    check(s["steps"] == failure["step"] - 1 and s["final_state"]["t"] < failure["t"], "final state is the last finite one")
    _, rows = read_csv(out / "trajectory.csv")
    check(rows[-1][0] == s["final_state"]["t"] and all(math.isfinite(v) for r in rows for v in r),
          "trajectory.csv must end with the last finite state")
    check(not (out / "plot.png").exists(), "the earlier outputs were not replaced")
    expect_no_staging_left(out)


# ---- the energy guard and the close-encounter floor (issue #5, docs/stability.md) ----------------

def harmonic_scene(dt, steps, guard=None, method="sesi2"):
    """A harmonic pair on E^2 whose relative coordinate has w = 1: Strang's stability limit is
    w dt = 2."""
    lines = ['name = "stiff"', "[space]", 'kind = "euclidean"', "dim = 2",
             "[[bodies]]", "mass = 1.0", "q = [1.0, 1.0]", "p = [0.0, 0.3]",
             "[[bodies]]", "mass = 1.0", "q = [0.0, 0.0]", "p = [0.0, -0.3]",
             "[[potential]]", 'kind = "harmonic-pair"', "k = 0.5",
             "[integrator]", f'method = "{method}"', f"dt = {dt!r}", f"t_end = {dt * steps!r}"]
    if guard is not None:
        lines.append(f"energy_guard = {guard}")
    return "\n".join(lines) + "\n"


def expect_run_failure(ctx, result, out, reason, *words):
    """Exit 3, one stderr line naming the step and time (and words), the summary marked
    incomplete with the reason, and only finite rows kept."""
    err = result.stderr
    check(result.returncode == 3, f"exit status {result.returncode}, expected 3: {err!r}")
    check(err.count("\n") == 1 and err.startswith("sesi: error: "), f"expected one line: {err!r}")
    s = summary(out)
    failure = s["failure"]
    check(s["complete"] is False and s["stop_reason"] == reason, f"stop_reason {s['stop_reason']!r}")
    check(f"step {failure['step']} " in err and f"t = {failure['t']:g}" in err, f"step and time: {err!r}")
    for word in words:
        check(word in err, f"stderr does not say {word!r}: {err!r}")
    _, rows = read_csv(out / "trajectory.csv")
    check(all(math.isfinite(v) for r in rows for v in r), "non-finite numbers in trajectory.csv")
    check(rows[-1][0] == s["final_state"]["t"], "trajectory.csv must end with the last good state")
    expect_no_staging_left(out)
    return s


@case
def energy_guard_trips_above_stability_limit(ctx):
    path = ctx.write("stiff.toml", harmonic_scene(2.04, 200))
    out = ctx.work / "out"
    s = expect_run_failure(ctx, ctx.run("run", path, "--out", out), out, "energy error exceeded",
                           "energy error", "|E - E0| = ", "energy_guard = 100")
    check(s["failure"]["step"] < 30, f"the guard tripped late: step {s['failure']['step']}")


@case
def energy_guard_quiet_below_stability_limit(ctx):
    path = ctx.write("stiff.toml", harmonic_scene(1.96, 2000))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--out", out, "-q"), "stable run at 0.98 of the limit")
    check(summary(out)["complete"] is True, "not complete")


@case
def energy_guard_off(ctx):
    # The same unstable run without the guard: nothing stops it (the energy grows by 1e20).
    path = ctx.write("stiff.toml", harmonic_scene(2.04, 60, guard="false"))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--out", out, "-q"), "energy_guard = false")
    check(summary(out)["energy"]["max_rel_error"] > 1e10, "the run should have blown up")


@case
def energy_guard_from_scene(ctx):
    # A tight guard set in the scene stops the (stable) seed scene at its first steps.
    text = (ctx.source / "examples" / "scenes" / "paper.toml").read_text()
    text = text.replace("[integrator]", "[integrator]\nenergy_guard = 1e-12", 1)
    path = ctx.write("tight.toml", text)
    out = ctx.work / "out"
    expect_run_failure(ctx, ctx.run("run", path, "--out", out, "--t-end", "10"), out, "energy error exceeded",
                       "energy_guard = 1e-12")


HEAD_ON = """name = "head-on"
# Two bodies falling onto each other from rest under cotangent gravity.
[space]
kind = "sphere"
dim = 2
[[bodies]]
mass = 1.0
q = [1.5707963267948966, -0.25]
[[bodies]]
mass = 1.0
q = [1.5707963267948966, 0.25]
[[potential]]
kind = "cotangent-gravity"
G = 1.0
{floor}
[integrator]
dt = 0.001
t_end = 1.0
output_every = 10
"""


@case
def close_encounter_head_on(ctx):
    path = ctx.write("head-on.toml", HEAD_ON.format(floor="min_distance = 0.05"))
    out = ctx.work / "out"
    s = expect_run_failure(ctx, ctx.run("run", path, "--out", out), out, "close encounter",
                           "bodies 1 and 2", "close-encounter floor 0.05", "cotangent-gravity")
    check(0.2 < s["failure"]["t"] < 0.3, f"collision time {s['failure']['t']}")


@case
def close_encounter_head_on_defaults(ctx):
    # With the default floor the steps jump over the encounter; the energy guard stops the run.
    path = ctx.write("head-on.toml", HEAD_ON.format(floor=""))
    out = ctx.work / "out"
    result = ctx.run("run", path, "--out", out)
    check(result.returncode == 3, f"exit status {result.returncode}: {result.stderr!r}")
    s = summary(out)
    check(s["stop_reason"] in ("close encounter", "energy error exceeded"), f"stop_reason {s['stop_reason']!r}")
    _, rows = read_csv(out / "trajectory.csv")
    check(all(math.isfinite(v) for r in rows for v in r), "non-finite numbers in trajectory.csv")
