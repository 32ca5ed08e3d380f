# Output directories (issue #12, item 4): nothing sesi did not write is ever deleted, a failed or
# interrupted re-run never replaces complete outputs, killed runs' staging folders are cleaned up
# (or named), two runs cannot share a directory, and write errors name DIR.
# Exec'd in check_program.py's namespace: Context, case, check, start_long_run, ... come from there.

import resource


def staging_dirs(out):
    """The staging directories beside out (not its lock file)."""
    out = pathlib.Path(out)
    return [p for p in out.parent.iterdir()
            if p.name.startswith(f".{out.name}.sesi-") and p.name != f".{out.name}.sesi-lock" and p.is_dir()]


def wait_for_run(out, process, timeout=60):
    """Wait until the run into out has made its staging directory (it has checked and locked out)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if any((p / ".sesi-staging").is_file() for p in staging_dirs(out)):
            time.sleep(0.2)  # into the steps
            return
        if process.poll() is not None:
            raise Failure(f"the run ended early with status {process.returncode}")
        time.sleep(0.02)
    raise Failure("no staging directory appeared")


def interrupt(process):
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=60)
    check(process.returncode == 130, f"exit status {process.returncode}, expected 130: {stderr!r}")
    return stderr.decode()


def dead_pid():
    """A process id that no process has now."""
    child = subprocess.Popen(["true"])
    child.wait()
    return child.pid


def tree(directory):
    """Every file under directory with its bytes."""
    directory = pathlib.Path(directory)
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


def warnings_in(stderr):
    return [line for line in stderr.splitlines() if line.startswith("sesi: warning: ")]


@case
def out_added_during_run_kept(ctx):
    out = ctx.work / "out"
    earlier_outputs(out)
    process = start_long_run(ctx, out)
    wait_for_run(out, process)
    (out / "notes.txt").write_text("my notes\n")
    (out / "analysis").mkdir()
    (out / "analysis" / "fit.py").write_text("print('fit')\n")
    stderr = interrupt(process)
    check((out / "notes.txt").read_text() == "my notes\n", "notes.txt added during the run was lost")
    check((out / "analysis" / "fit.py").read_text() == "print('fit')\n", "analysis/ added during the run was lost")
    check(summary(out)["stop_reason"] == "interrupted", "the new outputs were not published")
    check(not (out / "plot.png").exists(), "the earlier run's plot should go with it")
    warnings = warnings_in(stderr)
    check(len(warnings) == 1 and "notes.txt" in warnings[0] and "analysis/" in warnings[0] and str(out) in warnings[0],
          f"expected one warning naming notes.txt and analysis/: {stderr!r}")
    check(".sesi-" not in stderr, f"stderr names a staging path: {stderr!r}")
    expect_no_staging_left(out)


@case
def out_made_during_run_kept(ctx):
    # DIR did not exist when the run started; the user makes it and puts a file in.
    out = ctx.work / "out"
    process = start_long_run(ctx, out)
    wait_for_run(out, process)
    out.mkdir()
    (out / "README").write_text("mine\n")
    stderr = interrupt(process)
    check((out / "README").read_text() == "mine\n", "README made during the run was lost")
    check(summary(out)["stop_reason"] == "interrupted", "the new outputs were not published")
    check(any("README" in w for w in warnings_in(stderr)), f"no warning names README: {stderr!r}")
    expect_no_staging_left(out)


@case
def interrupted_rerun_keeps_complete_outputs(ctx):
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "1", "--out", out, "-q"), "first run")
    before = snapshot(out)
    process = start_long_run(ctx, out)
    wait_for_run(out, process)
    stderr = interrupt(process)
    expect_untouched(out, before)
    check(summary(out)["complete"] is True, "the complete run was replaced")
    incomplete = ctx.work / "out.incomplete"
    s = summary(incomplete)
    check(s["complete"] is False and s["stop_reason"] == "interrupted", f"{incomplete}: {s['stop_reason']}")
    lines = stderr.splitlines()
    check(len(lines) == 2 and lines[0].startswith("sesi: warning: ") and lines[1].startswith("sesi: error: "),
          f"expected a warning and an error line: {stderr!r}")
    check(str(incomplete) in lines[0] and "complete earlier run" in lines[0], f"warning: {lines[0]!r}")
    check(f"outputs so far are in {incomplete}," in lines[1], f"the error line does not name {incomplete}: {lines[1]!r}")
    # Again: the incomplete outputs are replaced, the complete ones still kept.
    process = start_long_run(ctx, out)
    wait_for_run(out, process)
    interrupt(process)
    expect_untouched(out, before)
    check(summary(incomplete)["stop_reason"] == "interrupted", "out.incomplete not replaced")
    check(not (ctx.work / "out.incomplete-2").exists(), "an incomplete run need not keep another incomplete one")
    expect_no_staging_left(incomplete)


@case
def failed_rerun_keeps_complete_outputs(ctx):
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "1", "--out", out, "-q"), "first run")
    before = snapshot(out)
    result = ctx.run("run", ctx.write("blowup.toml", BLOWUP), "--out", out)
    check(result.returncode == 3, f"exit status {result.returncode}, expected 3: {result.stderr!r}")
    expect_untouched(out, before)
    incomplete = ctx.work / "out.incomplete"
    check(summary(incomplete)["complete"] is False, "the failed run's outputs are not in out.incomplete")
    check(f"in {incomplete}, marked incomplete" in result.stderr, f"stderr: {result.stderr!r}")


@case
def stale_staging_removed(ctx):
    out = ctx.work / "out"
    stale = ctx.work / ".out.sesi-Ab12Cd"  # as a SIGKILLed run leaves it
    stale.mkdir()
    (stale / ".sesi-staging").write_text(f"{dead_pid()}\n")
    (stale / "trajectory.csv").write_text("t\n0\n")
    (stale / "diagnostics.csv").write_text("t\n0\n")
    (stale / "summary.json.tmp").write_text("{")
    (ctx.work / ".out.sesi-lock").write_text("1\n")  # a killed run's lock file, no longer held
    result = ctx.run("run", "--t-end", "1", "--out", out, "-q")
    check(result.returncode == 0, f"exit status {result.returncode}: {result.stderr!r}")
    check(not stale.exists(), f"{stale} was not removed")
    lines = result.stderr.splitlines()
    check(len(lines) == 1 and lines[0].startswith("sesi: warning: ") and "removed" in lines[0] and str(stale) in lines[0],
          f"expected one warning naming {stale}: {result.stderr!r}")
    check(summary(out)["complete"] is True, "the run did not complete")
    expect_no_staging_left(out)


@case
def stale_lookalikes_left(ctx):
    out = ctx.work / "out"
    folders = {
        ".out.sesi-Xy34Zw": (None, {"notes.txt": "no marker: not sesi's\n"}),
        ".out.sesi-Qr56St": (dead_pid(), {"trajectory.csv": "t\n", "mine.txt": "a user's file\n"}),
        ".out.sesi-Lm78No": (dead_pid(), {"trajectory.csv": "t\n", "checkpoint": "state\n"}),
        ".out.sesi-Ef90Gh": (os.getpid(), {"trajectory.csv": "t\n"}),  # its owner is alive
        ".out.sesi-Ij12Kl.old": (None, {"summary.json": "earlier\n"}),
    }
    for name, (pid, files) in folders.items():
        folder = ctx.work / name
        folder.mkdir()
        if pid is not None:
            (folder / ".sesi-staging").write_text(f"{pid}\n")
        for file, text in files.items():
            (folder / file).write_text(text)
    before = {name: tree(ctx.work / name) for name in folders}
    result = ctx.run("run", "--t-end", "1", "--out", out, "-q")
    check(result.returncode == 0, f"exit status {result.returncode}: {result.stderr!r}")
    for name in folders:
        check(tree(ctx.work / name) == before[name], f"{name} was changed")
    lines = result.stderr.splitlines()
    check(len(lines) == 1 and lines[0].startswith("sesi: warning: ") and "removed" not in lines[0],
          f"expected one warning line: {result.stderr!r}")
    for name in folders:
        check(str(ctx.work / name) in lines[0], f"the warning does not name {name}: {lines[0]!r}")
    check("checkpoint" in lines[0] and "mine.txt" in lines[0] and "no sesi marker" in lines[0],
          f"the warning does not say why: {lines[0]!r}")
    check(summary(out)["complete"] is True, "the run did not complete")


@case
def concurrent_runs_refused(ctx):
    out = ctx.work / "out"
    process = start_long_run(ctx, out)
    try:
        wait_for_run(out, process)
        before = tree(staging_dirs(out)[0])
        second = ctx.run("run", "--t-end", "1", "--out", out)
        expect_input_error(second, key=f"--out {out}", text=f"is in use by another sesi run (pid {process.pid})")
        check(tree(staging_dirs(out)[0]).keys() == before.keys(), "the second run touched the first one's staging")
        # The default output directory is locked the same way, whatever path names it.
        second = ctx.run("run", "--t-end", "1", "--out", f"{out}/")
        expect_input_error(second, text="is in use by another sesi run")
    finally:
        stderr = interrupt(process)
    check(stderr.count("\n") == 1, f"the first run was disturbed: {stderr!r}")
    check(summary(out)["stop_reason"] == "interrupted", "the first run's outputs are missing")
    expect_no_staging_left(out)
    expect_ok(ctx.run("run", "--t-end", "1", "--out", out, "-q"), "a run after the first ended")


@case
def out_trailing_slash(ctx):
    out = ctx.work / "out"
    earlier_outputs(out)
    expect_ok(ctx.run("run", "--t-end", "1", "--out", f"{out}/", "-q"), "--out DIR/")
    check(summary(out)["complete"] is True and not (out / "plot.png").exists(), "DIR/ not replaced")
    check(not any(p.name.startswith(".") for p in out.iterdir()), f"hidden files in {out}: {list(out.iterdir())}")
    expect_no_staging_left(out)


def limit_file_size(size):
    def apply():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a failed write, not a killed process
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
    return apply


def expect_write_error(result, out, reason):
    err = result.stderr
    check(result.returncode not in (0, 2), f"exit status {result.returncode}: {err!r}")
    check(err.count("\n") == 1 and err.startswith("sesi: error: "), f"expected one line: {err!r}")
    check(f"cannot write {out}/" in err and reason in err, f"the error does not name {out}: {err!r}")
    check(".sesi-" not in err, f"the error names the staging path: {err!r}")
    expect_no_staging_left(out)


@case
def write_error_names_out(ctx):
    # A file size limit stands for a full disk: the writes fail with EFBIG.
    out = ctx.work / "out"
    before = earlier_outputs(out)
    result = subprocess.run([ctx.sesi, "run", "--t-end", "100", "--out", str(out), "-q"], cwd=ctx.work,
                            capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL,
                            preexec_fn=limit_file_size(20000))
    expect_write_error(result, out, "File too large")
    expect_untouched(out, before)


@case
def full_disk_names_out(ctx):
    # A 64 KiB tmpfs holds the output directory and its staging directory (root only).
    disk = ctx.work / "disk"
    disk.mkdir()
    if os.geteuid() != 0 or shutil.which("mount") is None:
        raise Skip("mounting a small tmpfs needs root")
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(disk)], capture_output=True)
    if mounted.returncode != 0:
        raise Skip(f"cannot mount a tmpfs: {mounted.stderr.decode().strip()}")
    try:
        out = disk / "out"
        result = ctx.run("run", "--out", out, "-q")
        expect_write_error(result, out, "No space left on device")
        check(not out.exists(), f"{out} was made by a failed run")
    finally:
        subprocess.run(["umount", str(disk)], check=True)
