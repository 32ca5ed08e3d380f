# The command line (src/cli): argument errors, --help and --version, the default scene and its
# default output directory, the progress bar and interrupted runs.
# Exec'd in check_program.py's namespace: case, check, Context, expect_input_error, earlier_outputs,
# start_long_run, ... come from there.

import pty
import select

POTENTIALS = ["chord-well", "cotangent-gravity", "central-cotangent", "harmonic-pair", "lennard-jones"]


# ---- command-line arguments --------------------------------------------------------------------

def arg_error(ctx, args, key, text):
    out = ctx.work / "out"
    before = earlier_outputs(out)
    result = ctx.run("run", *args, "--out", out)
    expect_input_error(result, key=key, text=text)
    expect_untouched(out, before)


@case
def args_dt_zero(ctx):
    arg_error(ctx, ["--dt", "0"], "--dt", "expected a finite, non-zero step")


@case
def args_dt_nan(ctx):
    arg_error(ctx, ["--dt", "nan"], "--dt", "got nan")


@case
def args_dt_inf(ctx):
    arg_error(ctx, ["--dt", "inf"], "--dt", "got inf")


@case
def args_dt_not_a_number(ctx):
    arg_error(ctx, ["--dt", "abc"], "", "--dt")


@case
def args_t_end_negative(ctx):
    arg_error(ctx, ["--t-end", "-1"], "--t-end", "expected a finite end time >= 0")


@case
def args_t_end_nan(ctx):
    arg_error(ctx, ["--t-end", "nan"], "--t-end", "got nan")


@case
def args_too_many_steps(ctx):
    arg_error(ctx, ["--dt", "1e-300"], "--dt/--t-end", "at most")


@case
def args_method_unknown(ctx):
    arg_error(ctx, ["--method", "sesi4-mclachan"], "--method", "did you mean 'sesi4-mclachlan'?")


@case
def args_output_every_zero(ctx):
    arg_error(ctx, ["--output-every", "0"], "--output-every", "expected an integer >= 1")


@case
def args_unknown_option(ctx):
    arg_error(ctx, ["--bogus"], "", "--bogus")


@case
def args_extra_positional(ctx):
    scene = ctx.scene("paper.toml")
    arg_error(ctx, [scene, scene], "", "not expected")


@case
def args_scene_missing(ctx):
    arg_error(ctx, [ctx.work / "no-such-scene.toml"], "", "cannot read the scene file")


@case
def args_scene_is_directory(ctx):
    arg_error(ctx, [ctx.work], "", "got a directory")


@case
def args_no_subcommand(ctx):
    result = ctx.run()
    expect_input_error(result, text="subcommand")


@case
def help_texts(ctx):
    top = ctx.run("--help")
    check(top.returncode == 0 and "run" in top.stdout, f"sesi --help: {top.returncode} {top.stdout!r}")
    run = ctx.run("run", "--help")
    check(run.returncode == 0, f"sesi run --help: {run.returncode}")
    for word in [*METHODS, *POTENTIALS, "--out", "--method", "--dt", "--t-end", "--quiet", "trajectory.csv",
                 "diagnostics.csv", "summary.json", "EXIT STATUS"]:
        check(word in run.stdout, f"sesi run --help does not mention {word}")
    version = ctx.run("--version")
    check(version.returncode == 0 and version.stdout.startswith("sesi "), f"--version: {version.stdout!r}")


# ---- the default scene -------------------------------------------------------------------------

REQUIRED_SUMMARY = {
    "method": str, "dt": float, "steps": int, "t_end": float, "wall_seconds": float, "complete": bool,
    "energy": {"initial": float, "final": float, "max_abs_error": float, "max_rel_error": float},
    "momentum_map": {"initial": list, "final": list, "max_abs_drift": float},
    "final_state": {"t": float, "bodies": list},
}


def expect_fields(data, schema, where="summary.json"):
    for key, kind in schema.items():
        check(key in data, f"{where} lacks {key!r}")
        if isinstance(kind, dict):
            expect_fields(data[key], kind, f"{where}.{key}")
        elif kind is float:
            check(isinstance(data[key], (int, float)) and not isinstance(data[key], bool),
                  f"{where}.{key} is not a number: {data[key]!r}")
        else:
            check(isinstance(data[key], kind), f"{where}.{key} is not a {kind.__name__}: {data[key]!r}")


@case
def default_scene(ctx):
    out = ctx.work / "paper"
    result = ctx.run("run", "--out", out)
    expect_ok(result, "sesi run")
    check("sesi4" in result.stdout and "8000 steps" in result.stdout, f"report: {result.stdout!r}")
    for name in OUTPUTS + ["exact.csv"]:
        check((out / name).is_file(), f"{name} missing")
    expect_no_staging_left(out)
    s = summary(out)
    expect_fields(s, REQUIRED_SUMMARY)
    check(s["complete"] is True and s["method"] == "sesi4" and s["steps"] == 8000, f"summary: {s}")
    check(s["dt"] == 0.1 and s["t_end"] == 800 and s["final_state"]["t"] == 800, "dt, t_end, final t")
    check('"dt": 0.10000000000000001' in (out / "summary.json").read_text(), "numbers not printed with %.17g")
    # The seed's energy (shared/paper-scene.md gives 15 digits).
    check(abs(s["energy"]["initial"] - 0.183243903882068) < 1e-15, f"initial energy {s['energy']['initial']}")
    for body in s["final_state"]["bodies"]:
        check(set(body) >= {"q", "p", "x", "v"} and len(body["q"]) == 2 and len(body["x"]) == 3, f"body {body}")

    header, rows = read_csv(out / "trajectory.csv")
    check(header[:8] == ["t", "b1_q1", "b1_q2", "b1_p1", "b1_p2", "b1_x1", "b1_x2", "b1_x3"], f"header {header}")
    check(len(header) == 1 + 3 * 7 and len(rows) == 8001, f"trajectory shape {len(header)} x {len(rows)}")
    first = rows[0]
    for b in range(3):
        q1, q2, p1, p2 = first[1 + 7 * b: 5 + 7 * b]
        check(q1 == math.pi / 4 and abs(q2 - 2 * math.pi * b / 3) < 1e-15 and p1 == 0.25
              and p2 == 0.1727174029854043, f"initial state of body {b + 1}: {first[1 + 7 * b: 5 + 7 * b]}")
    last_x = rows[-1][5:8]
    check(last_x == s["final_state"]["bodies"][0]["x"], "final x differs between summary and trajectory")

    # Every step is a row here, so the summary's maxima must be the maxima over the rows.
    dheader, drows = read_csv(out / "diagnostics.csv")
    check(dheader == ["t", "energy", "energy_error", "M1_2", "M1_3", "M2_3"], f"diagnostics header {dheader}")
    max_error = max(abs(r[2]) for r in drows)
    check(max_error == s["energy"]["max_abs_error"], f"max energy error {max_error} vs {s['energy']['max_abs_error']}")
    check(drows[0][3:] == s["momentum_map"]["initial"] and drows[-1][3:] == s["momentum_map"]["final"],
          "momentum map in summary and diagnostics differ")
    drift = max(abs(r[k] - drows[0][k]) for r in drows for k in range(3, 6))
    check(drift == s["momentum_map"]["max_abs_drift"], "momentum drift in summary and diagnostics differ")

    eheader, erows = read_csv(out / "exact.csv")
    check(len(erows) == len(rows) and eheader[0] == "t", "exact.csv shape")
    worst = max(math.dist(r[5:8], e[1:4]) for r, e in zip(rows, erows))
    check(abs(worst - s["exact"]["max_position_error"][0]) <= 1e-15, "exact position error inconsistent")


@case
def default_out_dir(ctx):
    result = ctx.run("run", "--t-end", "1", "--quiet", cwd=ctx.work)
    expect_ok(result, "sesi run --quiet")
    check(result.stdout == "", f"--quiet printed {result.stdout!r}")
    check((ctx.work / "sesi-out" / "paper" / "summary.json").is_file(), "./sesi-out/paper not written")


@case
def default_equals_paper_file(ctx):
    ctx.run("run", "--t-end", "20", "--out", ctx.work / "a", "-q")
    expect_ok(ctx.run("run", ctx.scene("paper.toml"), "--t-end", "20", "--out", ctx.work / "b", "-q"), "paper.toml")
    for name in ["trajectory.csv", "diagnostics.csv", "exact.csv"]:
        check((ctx.work / "a" / name).read_bytes() == (ctx.work / "b" / name).read_bytes(),
              f"{name}: the embedded scene and examples/scenes/paper.toml differ")


# ---- interrupted runs and the progress bar -----------------------------------------------------

@case
def interrupted_run(ctx):
    out = ctx.work / "out"
    process = start_long_run(ctx, out)
    time.sleep(0.5)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=60)
    check(process.returncode == 130, f"exit status {process.returncode}, expected 130")
    check(stderr.decode().count("\n") == 1 and b"interrupted" in stderr, f"stderr {stderr!r}")
    s = summary(out)
    check(s["complete"] is False and s["stop_reason"] == "interrupted", f"summary {s['stop_reason']}")
    expect_no_staging_left(out)


def run_on_terminal(ctx, quiet):
    """Run a long scene with stderr on a pseudo-terminal for 1.8 s, then interrupt it; return
    what reached the terminal."""
    master, slave = pty.openpty()
    process = start_long_run(ctx, ctx.work / "out", stderr=slave, quiet=quiet)
    os.close(slave)
    seen = b""
    deadline = time.monotonic() + 1.8
    while time.monotonic() < deadline:
        ready, _, _ = select.select([master], [], [], 0.05)
        if ready:
            try:
                seen += os.read(master, 4096)
            except OSError:
                break
    process.send_signal(signal.SIGINT)
    process.wait(timeout=60)
    while True:
        ready, _, _ = select.select([master], [], [], 0.2)
        if not ready:
            break
        try:
            chunk = os.read(master, 4096)
        except OSError:
            break
        if not chunk:
            break
        seen += chunk
    os.close(master)
    return seen.decode(errors="replace")


@case
def progress_bar_on_terminal(ctx):
    seen = run_on_terminal(ctx, quiet=False)
    check("%" in seen and "[" in seen and "left" in seen, f"no progress bar on the terminal: {seen[:300]!r}")
    check("\r\x1b[K" in seen, "the progress bar was not erased")


@case
def no_progress_bar_when_quiet(ctx):
    seen = run_on_terminal(ctx, quiet=True)
    check("%" not in seen and "left" not in seen, f"--quiet drew a progress bar: {seen[:300]!r}")


@case
def no_progress_bar_without_terminal(ctx):
    out = ctx.work / "out"
    process = start_long_run(ctx, out)
    time.sleep(1.5)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    check(b"%" not in stderr and b"\r" not in stderr, f"progress bar on a pipe: {stderr!r}")
