# The step profile, `sesi run --profile` (issue #27; include/sesi/profile.hpp, docs/benchmarks.md
# "Profile of a step"). Exec'd inside check_program.py: its helpers (case, check, Context, ...) and
# the other cases files' (threads_sphere_scene, threads_outputs) are in scope.
#
# Profiling reads clocks only: the outputs are the same bytes with and without it. profile.csv is
# an output like the others (in the manifest), its phases add up to the step, and a resumed run's
# profile covers its own steps.

PROFILE_PHASES = ["other", "drift", "force", "neighbours", "thermostat", "checks", "output", "checkpoint"]


def read_profile(path):
    """(comment lines, rows as dicts) of a profile.csv; empty cells as None."""
    lines = pathlib.Path(path).read_text().splitlines()
    comments = [line for line in lines if line.startswith("#")]
    body = [line for line in lines if not line.startswith("#")]
    header = body[0].split(",")
    check(header == ["phase", "thread", "calls", "wall_seconds", "loop_seconds", "busy_seconds",
                     "serial_seconds", "share"], f"profile.csv header: {header}")
    rows = []
    for line in body[1:]:
        cells = line.split(",")
        check(len(cells) == len(header), f"profile.csv row {line!r}: {len(cells)} cells")
        row = dict(zip(header, cells))
        for key in header[2:]:
            row[key] = None if row[key] == "" else float(row[key])
        rows.append(row)
    return comments, rows


def expect_profile(out, threads, steps, result):
    """out/profile.csv is listed in the manifest, has every phase's total and per-thread rows, and
    adds up; the stderr table names the serial fraction."""
    check("profile.csv" in (out / "sesi-manifest.txt").read_text().splitlines(), "profile.csv is not in the manifest")
    comments, rows = read_profile(out / "profile.csv")
    check(any(f"{threads} threads, {steps} steps" in c for c in comments), f"profile.csv comments: {comments[:2]}")
    totals = {r["phase"]: r for r in rows if r["thread"] == "all"}
    check(list(totals) == PROFILE_PHASES + ["step"], f"profile.csv phases: {list(totals)}")
    threads_seen = sorted({r["thread"] for r in rows if r["thread"] != "all"})
    check(threads_seen == [str(t) for t in range(threads)], f"profile.csv threads: {threads_seen}")
    step = totals["step"]
    check(step["calls"] == steps, f"profile.csv: step calls {step['calls']}, expected {steps}")
    # Values are printed to 1e-9 s, each rounded by at most 0.5e-9: a sum of 8 by 4e-9 more.
    walls = sum(totals[p]["wall_seconds"] for p in PROFILE_PHASES)
    check(abs(walls - step["wall_seconds"]) <= 4.5e-9, f"phases add up to {walls}, step {step['wall_seconds']}")
    for p in PROFILE_PHASES + ["step"]:
        r = totals[p]
        check(abs(r["serial_seconds"] - (r["wall_seconds"] - r["loop_seconds"])) <= 1.5e-9 + (4.5e-9 if p == "step" else 0),
              f"{p}: serial != wall - loop: {r}")
        check(r["loop_seconds"] <= r["wall_seconds"] + 1e-9, f"{p}: loops longer than the phase: {r}")
    # Every step drifts and kicks; the first row is outside the window, the others inside.
    for p in ("drift", "force", "checks", "output"):
        check(totals[p]["calls"] > 0, f"profile.csv: no {p} calls")
    check(totals["force"]["loop_seconds"] > 0, "no parallel loop in the force phase")
    check("serial fraction" in result.stderr and "profile of" in result.stderr,
          f"no profile table on stderr: {result.stderr!r}")
    return totals


def expect_ok_profiled(result, what):
    check(result.returncode == 0, f"{what}: exit status {result.returncode}, stderr: {result.stderr.strip()}")
    check(result.stderr.startswith("sesi: profile of "), f"{what}: stderr is not the profile: {result.stderr!r}")


@case
def profile_same_outputs(ctx):
    # 600 bodies on two threads (threads_for: a thread per 256 bodies): the loops run on both.
    scene = ctx.write("profile-lj.toml", threads_sphere_scene(600, 1.0, 41, t_end="0.1", dt="0.005"))
    plain, profiled = ctx.work / "profile-plain", ctx.work / "profile-on"
    expect_ok(ctx.run("run", scene, "--threads", 2, "--quiet", "--out", plain), "run without --profile")
    result = ctx.run("run", scene, "--threads", 2, "--quiet", "--profile", "--out", profiled)
    expect_ok_profiled(result, "run --profile")
    check(not (plain / "profile.csv").exists(), "profile.csv written without --profile")
    a, b = threads_outputs(plain), threads_outputs(profiled)
    b.pop("profile.csv")
    a["sesi-manifest.txt"] = a["sesi-manifest.txt"].replace(b"diagnostics.csv\n", b"diagnostics.csv\nprofile.csv\n")
    check(sorted(a) == sorted(b), f"files {sorted(a)} against {sorted(b)}")
    for name in a:
        check(a[name] == b[name], f"{name} differs with --profile")
    expect_profile(profiled, 2, 20, result)


@case
def profile_resumed_steps(ctx):
    # A resumed run's profile covers its own steps: 20 steps to t = 0.1, checkpoint at 10. On one
    # thread the loops over 600 bodies (>= 512: shared on two threads) are parallel regions still.
    scene = ctx.write("profile-resume.toml", threads_sphere_scene(600, 1.0, 42, t_end="0.1", dt="0.005"))
    out = ctx.work / "profile-resume"
    expect_ok(ctx.run("run", scene, "--threads", 1, "--t-end", "0.05", "--checkpoint-every", 10, "--quiet",
                      "--out", out), "first half")
    result = ctx.run("resume", out, "--t-end", "0.1", "--threads", 1, "--quiet", "--profile")
    expect_ok_profiled(result, "resume --profile")
    expect_profile(out, 1, 10, result)
