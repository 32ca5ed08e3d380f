# Checkpoints, `sesi resume` and signals (issue #12; docs/scene-format.md, "Checkpoints and
# resume"). Exec'd inside check_program.py: its helpers (case, check, Context, ...) are in scope.
#
# A resumed run must equal an uninterrupted one byte for byte: every output file, and
# summary.json but for its wall time (and the lines that say how the run was stopped).

def output_files(out):
    """Every file of an output directory but the checkpoint, by name; summary.json parsed, without
    its wall time; the manifest's names but the checkpoint's (a resumed run always has one)."""
    files = {}
    for path in sorted(pathlib.Path(out).iterdir()):
        if path.name == "checkpoint":
            continue
        if path.name == "sesi-manifest.txt":
            lines = path.read_text().splitlines()
            files[path.name] = [lines[0]] + [n for n in lines[1:] if n != "checkpoint"]
            on_disk = sorted(p.name for p in pathlib.Path(out).iterdir() if p.name != path.name)
            check(sorted(lines[1:]) == on_disk, f"{out}: the manifest lists {lines[1:]}, the directory holds {on_disk}")
        elif path.name == "summary.json":
            data = json.loads(path.read_text())
            data.pop("wall_seconds")
            files[path.name] = data
        else:
            files[path.name] = path.read_bytes()
    return files


def expect_same_outputs(resumed, reference, what):
    a, b = output_files(resumed), output_files(reference)
    check(sorted(a) == sorted(b), f"{what}: files {sorted(a)} against {sorted(b)}")
    for name in a:
        check(a[name] == b[name], f"{what}: {name} differs from the uninterrupted run's")


def resume_extends(ctx, scene, t1, t2, every, *extra):
    """Run scene to t1 with checkpoints every `every` steps, resume it to t2, and compare with one
    run to t2."""
    first, whole = ctx.work / f"first-{t1}", ctx.work / f"whole-{t2}"
    args = ["--checkpoint-every", str(every), "--quiet", *extra]
    expect_ok(ctx.run("run", *scene, "--t-end", t2, "--out", whole, *args), "uninterrupted run")
    expect_ok(ctx.run("run", *scene, "--t-end", t1, "--out", first, *args), "first part")
    check((first / "checkpoint").is_file(), "no checkpoint written")
    expect_ok(ctx.run("resume", first, "--t-end", t2, "--quiet"), "sesi resume")
    expect_same_outputs(first, whole, f"{' '.join(map(str, scene))} resumed at {t1}")


@case
def resume_extends_paper(ctx):
    # The default scene: exact.csv too; 1.05 ends on a partial output row that the resumed run
    # must cut.
    resume_extends(ctx, [], "1.05", "3", 4, "--output-every", "3")


@case
def resume_extends_sphere_recharted(ctx):
    resume_extends(ctx, [ctx.scene("sphere-pole-crossing.toml")], "7.3", "20", 50)


@case
def resume_extends_hyperbolic_recharted(ctx):
    resume_extends(ctx, [ctx.scene("hyperbolic-kepler-xv.toml")], "3.33", "8", 25, "--output-every", "7")


@case
def resume_extends_euclidean(ctx):
    resume_extends(ctx, [ctx.scene("euclidean-figure-eight-qp.toml")], "1.01", "2.5", 10)


@case
def resume_every_method(ctx):
    for method in METHODS:
        resume_extends(ctx, [ctx.scene("sphere-pole-crossing.toml"), "--method", method], "2.3", "5", 30)


@case
def resume_h5md(ctx):
    probe = ctx.run("run", "--t-end", "0", "--trajectory-format", "h5md", "--out", ctx.work / "probe", "-q")
    if probe.returncode != 0:
        raise Skip("sesi is built without HDF5")
    resume_extends(ctx, [], "1.05", "3", 4, "--output-every", "3", "--trajectory-format", "h5md")


def stop_default_run(ctx, out, signals, scene=None, *args):
    """Start a long run of the default scene (or scene), send the signals 0.4 s apart after 0.6 s,
    and return the finished process with its stderr."""
    command = [ctx.sesi, "run", *([scene] if scene else []), "--t-end", "1e5", "--output-every", "97",
               "--out", str(out), "--quiet", *map(str, args)]
    process = subprocess.Popen(command, cwd=ctx.work, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               stdin=subprocess.DEVNULL)
    time.sleep(0.6)
    for s in signals:
        process.send_signal(s)
        time.sleep(0.4)
    _, stderr = process.communicate(timeout=120)
    return process, stderr.decode()


def resume_after(ctx, signum):
    out = ctx.work / "out"
    process, err = stop_default_run(ctx, out, [signum])
    check(process.returncode == 130, f"exit status {process.returncode}, expected 130: {err!r}")
    check(err.count("\n") == 1 and f"sesi resume {out}" in err, f"stderr does not say how to resume: {err!r}")
    check(summary(out)["complete"] is False, "the stopped run's summary is not marked incomplete")
    stopped_at = json.loads(json.dumps(summary(out)["final_state"]["step"]))
    # Go on to a little beyond the stop, and compare with one run there.
    t2 = f"{(stopped_at + 200) * 0.1:.1f}"
    expect_ok(ctx.run("resume", out, "--t-end", t2, "--quiet"), "sesi resume")
    whole = ctx.work / "whole"
    expect_ok(ctx.run("run", "--t-end", t2, "--output-every", "97", "--out", whole, "--quiet"), "uninterrupted run")
    expect_same_outputs(out, whole, f"resumed after signal {signum}")


@case
def resume_after_sigint(ctx):
    resume_after(ctx, signal.SIGINT)


@case
def resume_after_sigterm(ctx):
    resume_after(ctx, signal.SIGTERM)


@case
def resume_after_sighup(ctx):
    resume_after(ctx, signal.SIGHUP)


@case
def second_signal_stops_at_once(ctx):
    # Steps slow enough (6000 bodies, all pairs, 17 stages: about a second) that a second signal
    # comes while the first still waits for the step to end: the second ends sesi at once, exit
    # 130, one line, and no unfinished checkpoint is left.
    scene = ctx.work / "slow.toml"
    subprocess.run([sys.executable, str(ctx.source / "tools" / "lattice_scene.py"), "6000", str(scene)],
                   check=True, capture_output=True)
    text = scene.read_text().split("[[potential]]")[0]
    scene.write_text(text + '[[potential]]\nkind = "harmonic-pair"\nk = 1e-6\nd0 = 0.0\n\n'
                     '[integrator]\nmethod = "sesi8-kahan-li"\ndt = 0.001\nt_end = 1000.0\n'
                     'output_every = 100000\n')
    out = ctx.work / "out"
    process = subprocess.Popen([ctx.sesi, "run", str(scene), "--out", str(out), "--quiet"], cwd=ctx.work,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
    # The run has started once its staging directory (.out.sesi-XXXXXX) exists: it is made just after
    # the scene is read. Reading takes a fraction of a second on a quiet machine, but seconds under
    # the sanitizers beside a test that keeps every core busy, so wait for it rather than a fixed time.
    deadline = time.monotonic() + 100
    while not any(p.name.startswith(".out.sesi-") for p in ctx.work.iterdir()):
        check(process.poll() is None and time.monotonic() < deadline,
              f"the run did not start (exit status {process.poll()})")
        time.sleep(0.02)
    time.sleep(0.2)  # past the first forces and outputs, into a step (a second or more)
    process.send_signal(signal.SIGINT)
    time.sleep(0.05)  # two signals sent together may arrive as one
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=120)
    err = stderr.decode()
    check(process.returncode == 130, f"exit status {process.returncode}: {err!r}")
    check(err.count("\n") == 1 and "interrupted again" in err, f"stderr {err!r}")
    leftovers = list(ctx.work.rglob("checkpoint.tmp"))
    check(not leftovers, f"unfinished checkpoints left: {leftovers}")


@case
def signal_while_reading(ctx):
    # A large scene takes a while to read; a signal then ends sesi at once with nothing written.
    scene = ctx.work / "big.toml"
    subprocess.run([sys.executable, str(ctx.source / "tools" / "lattice_scene.py"), "200000", str(scene)],
                   check=True, capture_output=True)
    out = ctx.work / "out"
    # Reading 2e5 bodies takes seconds; should a fast machine read it before the signal, try once
    # more with an earlier one (a skip would hide the case: make test counts skips as failures).
    for delay in (0.3, 0.1):
        process = subprocess.Popen([ctx.sesi, "run", str(scene), "--out", str(out), "--t-end", "0"], cwd=ctx.work,
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
        time.sleep(delay)
        process.send_signal(signal.SIGTERM)
        _, stderr = process.communicate(timeout=120)
        err = stderr.decode()
        if process.returncode != 0:
            break
        shutil.rmtree(out)
    check(process.returncode != 0, "the scene was read before the signal came, twice")
    check(process.returncode == 130, f"exit status {process.returncode}: {err!r}")
    check(err.count("\n") == 1 and "nothing written" in err, f"stderr {err!r}")
    check(not out.exists(), "an output directory was created")
    check(not [p for p in ctx.work.iterdir() if p.name.startswith(".out")], "a staging directory was left")


@case
def guard_keeps_last_checkpoint(ctx):
    # Above Strang's stability limit the energy guard stops the run; the checkpoint kept is the
    # last one before, at a multiple of checkpoint_every.
    path = ctx.write("stiff.toml", harmonic_scene(2.04, 200))
    out = ctx.work / "out"
    result = ctx.run("run", path, "--out", out, "--checkpoint-every", "2")
    s = expect_run_failure(ctx, result, out, "energy error exceeded", "last good checkpoint")
    head = (out / "checkpoint").read_bytes().split(b"\n")[0]
    check(head.startswith(b"sesi-checkpoint 1 "), f"checkpoint header {head!r}")
    text = (out / "checkpoint").read_bytes()
    step = int(text.split(b"\nstep ")[1].split(b"\n")[0])
    check(step % 2 == 0 and step < s["failure"]["step"], f"checkpoint at step {step}, failure at {s['failure']['step']}")


def bad_checkpoint(ctx, mutate, text):
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "1", "--checkpoint-every", "5", "--out", out, "-q"), "run")
    path = out / "checkpoint"
    path.write_bytes(mutate(path.read_bytes()))
    before = snapshot(out)
    result = ctx.run("resume", out)
    expect_input_error(result, file=str(path), text=text)
    expect_untouched(out, before)


@case
def resume_refuses_truncated_checkpoint(ctx):
    bad_checkpoint(ctx, lambda b: b[: len(b) // 2], "truncated")


@case
def resume_refuses_corrupted_checkpoint(ctx):
    def flip(b):
        b = bytearray(b)
        b[len(b) // 2] ^= 0x01
        return bytes(b)
    bad_checkpoint(ctx, flip, "checksum")


@case
def resume_refuses_foreign_file(ctx):
    bad_checkpoint(ctx, lambda b: b"[space]\nkind = \"sphere\"\n", "not a sesi checkpoint")


@case
def resume_refuses_other_version(ctx):
    bad_checkpoint(ctx, lambda b: b.replace(b"sesi-checkpoint 1 ", b"sesi-checkpoint 9 ", 1), "version 9")


@case
def resume_without_checkpoint(ctx):
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "1", "--out", out, "-q"), "run")
    expect_input_error(ctx.run("resume", out), text="no checkpoint")


@case
def resume_before_checkpoint_refused(ctx):
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "2", "--checkpoint-every", "10", "--out", out, "-q"), "run")
    expect_input_error(ctx.run("resume", out, "--t-end", "0.5"), key="--t-end", text="after the end of the run")


@case
def resume_killed_run(ctx):
    # SIGKILL leaves the staging directory with the last periodic checkpoint; `sesi resume DIR`
    # finds it there and goes on into DIR, equal to an uninterrupted run.
    out = ctx.work / "out"
    settings = ["--output-every", "13", "--checkpoint-every", "500", "--quiet"]
    process = subprocess.Popen([ctx.sesi, "run", "--t-end", "1e5", "--out", str(out), *settings], cwd=ctx.work,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
    # Kill it once its first periodic checkpoint is there (polled, not slept: a loaded machine is slow).
    deadline = time.monotonic() + 120
    staging = []
    while not staging and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.05)
        staging = [p for p in ctx.work.iterdir() if p.name.startswith(".out.sesi-") and (p / "checkpoint").exists()]
    process.kill()
    process.wait(timeout=60)
    check(bool(staging), "no periodic checkpoint within 120 s")
    text = (staging[0] / "checkpoint").read_bytes()
    step = int(text.split(b"\nstep ")[1].split(b"\n")[0])
    t_end = f"{(step + 321) * 0.1:.1f}"
    expect_ok(ctx.run("resume", out, "--t-end", t_end, "--quiet"), "sesi resume of a killed run")
    whole = ctx.work / "whole"
    expect_ok(ctx.run("run", "--t-end", t_end, "--out", whole, *settings), "uninterrupted run")
    expect_same_outputs(out, whole, "resumed after SIGKILL")


# ---- issue #24: a finished run keeps a checkpoint at its end; one step number; edited checkpoints

import re


def checkpoint_step(path):
    return int(pathlib.Path(path).read_bytes().split(b"\nstep ")[1].split(b"\n")[0])


def expect_end_checkpoint_extends(ctx, t1, t2, every, *settings):
    """Run to t1 with checkpoints every `every` steps; its checkpoint must be at its end (or the
    last step every longer run checks), survive a resume that has nothing to do, and a resume to
    t2 must equal one run to t2."""
    first, whole = ctx.work / f"first-{t1}", ctx.work / f"whole-{t1}-{t2}"
    args = ["--checkpoint-every", str(every), "--quiet", *settings]
    expect_ok(ctx.run("run", "--t-end", t1, "--out", first, *args), "first part")
    before = output_files(first)
    step = checkpoint_step(first / "checkpoint")
    check(step > (round(float(t1) / 0.1) // every) * every, f"the checkpoint is at step {step}, not at the run's end")
    expect_ok(ctx.run("resume", first, "--quiet"), "sesi resume of a finished run")
    check((first / "checkpoint").is_file(), "sesi resume of a finished run removed its checkpoint")
    check(checkpoint_step(first / "checkpoint") == step, "the finished run's checkpoint moved")
    check(output_files(first) == before, "sesi resume of a finished run changed its outputs")
    expect_ok(ctx.run("resume", first, "--t-end", t2, "--quiet"), "sesi resume --t-end of a finished run")
    check((first / "checkpoint").is_file(), "the extended run has no checkpoint")
    expect_ok(ctx.run("run", "--t-end", t2, "--out", whole, *args), "uninterrupted run")
    expect_same_outputs(first, whole, f"run to {t1}, resumed to {t2}")


@case
def resume_checkpoint_at_off_grid_end(ctx):
    # 330 steps of 0.01 end at t = 3.3, not at 330 * 0.01 = 3.3000000000000003 as a longer run's
    # step 330 does: no checkpoint (periodic, every 30, or the end's) may sit at that last step.
    resume_extends(ctx, [ctx.scene("sphere-pole-crossing.toml"), "--method", "sesi2"], "3.3", "5", 30)


@case
def resume_finished_run_keeps_checkpoint(ctx):
    # 30 steps, checkpoints every 7: the last periodic one (28) is before the end (30).
    expect_end_checkpoint_extends(ctx, "3", "6", 7, "--output-every", "4")


@case
def resume_finished_run_shortened_last_step(ctx):
    # t = 3.05: 31 steps, the last one half a step; the end checkpoint is at step 30, whole.
    expect_end_checkpoint_extends(ctx, "3.05", "6", 7, "--output-every", "4")


@case
def resume_finished_run_sparse_checks(ctx):
    # check_every 4, rows every 5: steps 29, 30, 31 are not all checked by a longer run; the end
    # checkpoint sits at 30 (a row), so the extended run's energy maxima equal one run's.
    expect_end_checkpoint_extends(ctx, "3.1", "6", 7, "--output-every", "5", "--check-every", "4")


def interrupt_late(ctx, out, *settings):
    """Start the default scene to t = 1e5, SIGINT it after 0.6 s (long past its only periodic
    checkpoint, if any), and return the step it stopped after and its stderr."""
    process, err = stop_default_run(ctx, out, [signal.SIGINT], None, *settings)
    check(process.returncode == 130, f"exit status {process.returncode}, expected 130: {err!r}")
    return summary(out)["final_state"]["step"], err


@case
def resume_after_late_sigint_keeps_checkpoint(ctx):
    # Checkpoints every 50 steps and a SIGINT after many: the resumed run ends past its last
    # periodic checkpoint and must still keep one at its end, for a later --t-end.
    out = ctx.work / "out"
    stopped, _ = interrupt_late(ctx, out, "--checkpoint-every", "50")
    # The resumed run ends before the next multiple of 50: it takes no periodic checkpoint.
    end = (stopped // 50 + 1) * 50 - 1
    end = end if end > stopped else stopped + 49
    t2, t3 = f"{end * 0.1:.1f}", f"{(end + 120) * 0.1:.1f}"
    expect_ok(ctx.run("resume", out, "--t-end", t2, "--quiet"), "sesi resume")
    check((out / "checkpoint").is_file(), "the resumed, finished run has no checkpoint")
    expect_ok(ctx.run("resume", out, "--t-end", t3, "--quiet"), "a second sesi resume --t-end")
    whole = ctx.work / "whole"
    expect_ok(ctx.run("run", "--t-end", t3, "--output-every", "97", "--checkpoint-every", "50", "--out", whole,
                      "--quiet"), "uninterrupted run")
    expect_same_outputs(out, whole, "interrupted, resumed, resumed again")


@case
def interrupted_message_one_step(ctx):
    # With checks only every 1000 steps the stop is rarely a checked step: the message, the last
    # row, the summary and the checkpoint must all name the same step, and the run go on as one.
    out = ctx.work / "out"
    stopped, err = interrupt_late(ctx, out, "--check-every", "1000")
    check(f"interrupted after step {stopped} " in err, f"the message does not name step {stopped}: {err!r}")
    check(checkpoint_step(out / "checkpoint") == stopped, f"checkpoint at {checkpoint_step(out / 'checkpoint')}")
    named = [int(n) for n in re.findall(r"step (\d+)", err)]
    check(named and all(n == stopped for n in named), f"the message names other steps: {err!r}")
    t2 = f"{(stopped + 200) * 0.1:.1f}"
    expect_ok(ctx.run("resume", out, "--t-end", t2, "--quiet"), "sesi resume")
    whole = ctx.work / "whole"
    expect_ok(ctx.run("run", "--t-end", t2, "--output-every", "97", "--check-every", "1000", "--out", whole,
                      "--quiet"), "uninterrupted run")
    expect_same_outputs(out, whole, "resumed after a stop between checks")


def fnv1a(data):
    h = 0xcbf29ce484222325
    for byte in data:
        h = ((h ^ byte) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return h


def rewrite_checkpoint(path, version=None, edit=lambda body: body):
    """The checkpoint at path with its body edited and its first line recomputed to match (what
    a hand edit that knows the format does)."""
    text = pathlib.Path(path).read_bytes()
    head, body = text.split(b"\n", 1)
    body = edit(body)
    old_version = int(head.split()[1])
    head = b"sesi-checkpoint %d %d %016x" % (version or old_version, len(body), fnv1a(body))
    pathlib.Path(path).write_bytes(head + b"\n" + body)


@case
def resume_refuses_version_mismatch(ctx):
    # A chart method's checkpoint (version 1) whose first line says 2: name the version that wrote it.
    def to_version_2(b):
        head, body = b.split(b"\n", 1)
        return head.replace(b"sesi-checkpoint 1 ", b"sesi-checkpoint 2 ", 1) + b"\n" + body
    bad_checkpoint(ctx, to_version_2, "written by format version 1, but its first line says version 2")
    err = ctx.run("resume", ctx.work / "out").stderr
    check("reads format version 1" in err and "and 2" in err, f"the message does not say what sesi reads: {err!r}")


@case
def resume_refuses_negative_mass(ctx):
    # The checksum recomputed by hand after making a mass negative: the scene reader's rule applies.
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "1", "--checkpoint-every", "5", "--out", out, "-q"), "run")
    path = out / "checkpoint"

    def negative_mass(body):
        head, rest = body.split(b"\nmasses ", 1)
        count, first, tail = rest.split(b" ", 2)
        return head + b"\nmasses " + count + b" -" + first + b" " + tail
    rewrite_checkpoint(path, edit=negative_mass)
    before = snapshot(out)
    expect_input_error(ctx.run("resume", out), file=str(path), key="bodies[1].mass", text="expected a finite number > 0")
    expect_untouched(out, before)
