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


# ---- issue #24: mount points, the run's manifest, --out . and --out "" -------------------------

def mounted(directory, *how):
    """Mount a tmpfs (or, with how, e.g. "--bind", what `how` says) on directory; Skip where
    mounting is not permitted."""
    directory.mkdir(exist_ok=True)
    if os.geteuid() != 0 or shutil.which("mount") is None:
        raise Skip("mounting on --out needs root and mount(8)")
    command = ["mount", *(how or ("-t", "tmpfs", "tmpfs")), str(directory)]
    if how:
        command.insert(-1, str(directory))  # mount --bind DIR DIR
    result = subprocess.run(command, capture_output=True)
    if result.returncode != 0:
        raise Skip(f"mounting is not permitted here: {result.stderr.decode().strip()}")


def expect_clean_mount(mp):
    """No staging directory or lock left inside the mount point or beside it."""
    inside = [p.name for p in mp.iterdir() if p.name.startswith(".sesi-")]
    check(not inside, f"staging folders or lock left in {mp}: {inside}")
    expect_no_staging_left(mp)


def run_into_mount_point(ctx, mp):
    args = ["--checkpoint-every", "50", "--output-every", "7", "--quiet"]
    result = ctx.run("run", "--t-end", "10", "--out", mp, *args)
    expect_ok(result, "sesi run --out MOUNT_POINT")
    names = sorted(p.name for p in mp.iterdir())
    check(names == ["checkpoint", "diagnostics.csv", "exact.csv", "sesi-manifest.txt", "summary.json",
                    "trajectory.csv"], f"outputs in the mount point: {names}")
    check(summary(mp)["complete"] is True, "the run is not complete")
    expect_clean_mount(mp)
    # Run again into it, with a user's picture there: it stays; the earlier outputs are replaced.
    (mp / "figure.png").write_bytes(b"a user's figure")
    result = ctx.run("run", "--t-end", "5", "--out", mp, *args)
    check(result.returncode == 0, f"a second run into the mount point: {result.returncode}, {result.stderr!r}")
    check((mp / "figure.png").read_bytes() == b"a user's figure", "the user's picture in the mount point was lost")
    check(summary(mp)["t_end"] == 5, "the earlier outputs were not replaced")
    expect_clean_mount(mp)
    # Go on from its end checkpoint, in place: equal to one run.
    expect_ok(ctx.run("resume", mp, "--t-end", "12", "--quiet"), "sesi resume MOUNT_POINT")
    whole = ctx.work / "whole"
    expect_ok(ctx.run("run", "--t-end", "12", "--out", whole, *args), "uninterrupted run")
    for name in ["trajectory.csv", "diagnostics.csv", "exact.csv"]:
        check((mp / name).read_bytes() == (whole / name).read_bytes(), f"resumed in the mount point: {name} differs")
    # An interrupted run never replaces the complete one: its outputs go to MP/incomplete.
    process = start_long_run(ctx, mp)
    deadline = time.monotonic() + 60
    while not any((p / ".sesi-staging").is_file() for p in mp.glob(".sesi-??????")):
        check(time.monotonic() < deadline and process.poll() is None, "the long run did not start")
        time.sleep(0.02)
    time.sleep(0.2)
    stderr = interrupt(process)
    check(summary(mp)["complete"] is True, "the complete run in the mount point was replaced")
    check(summary(mp / "incomplete")["stop_reason"] == "interrupted", f"no outputs in {mp}/incomplete: {stderr!r}")
    expect_clean_mount(mp)


@case
def out_mount_point(ctx):
    # A tmpfs as --out: it cannot be renamed over; the run writes into it (issue #24).
    mp = ctx.work / "mp"
    mounted(mp)
    try:
        run_into_mount_point(ctx, mp)
    finally:
        subprocess.run(["umount", str(mp)], check=True)


@case
def out_bind_mount_point(ctx):
    # A bind mount of a directory on itself: the same device as its parent, still a mount point.
    mp = ctx.work / "mp"
    mounted(mp, "--bind")
    try:
        run_into_mount_point(ctx, mp)
    finally:
        subprocess.run(["umount", str(mp)], check=True)


@case
def user_pictures_kept(ctx):
    # Pictures a user put into a finished run's directory are theirs: a run repeated into it
    # replaces only what its manifest lists (and a plot tools/plot_run.py added to it).
    out = ctx.work / "out"
    expect_ok(ctx.run("run", "--t-end", "1", "--out", out, "-q"), "first run")
    manifest = (out / "sesi-manifest.txt").read_text().splitlines()
    check(manifest[0].startswith("# sesi-manifest 1:"), f"manifest: {manifest[0]!r}")
    on_disk = sorted(p.name for p in out.iterdir() if p.name != "sesi-manifest.txt")
    check(sorted(manifest[1:]) == on_disk, f"the manifest lists {manifest[1:]}, the directory holds {on_disk}")
    mine = {"figure.png": b"png", "paper.pdf": b"pdf", "sketch.svg": b"<svg/>"}
    for name, data in mine.items():
        (out / name).write_bytes(data)
    (out / "plot.png").write_bytes(b"sesi's plot")  # as tools/plot_run.py writes and lists it
    with (out / "sesi-manifest.txt").open("a") as f:
        f.write("plot.png\n")
    result = ctx.run("run", "--t-end", "2", "--out", out, "-q")
    check(result.returncode == 0, f"exit status {result.returncode}: {result.stderr!r}")
    for name, data in mine.items():
        check((out / name).is_file() and (out / name).read_bytes() == data, f"the user's {name} was not kept")
    check(not (out / "plot.png").exists(), "the earlier run's plot (in its manifest) was kept")
    check(summary(out)["t_end"] == 2, "the earlier outputs were not replaced")
    warnings = warnings_in(result.stderr)
    check(len(warnings) == 1 and all(name in warnings[0] for name in mine), f"expected one warning naming them: "
          f"{result.stderr!r}")
    expect_no_staging_left(out)


@case
def out_current_directory_refused(ctx):
    # --out . (or a directory above the current one) would replace where the user works.
    cwd = ctx.work / "here"
    cwd.mkdir()
    (cwd / "notes.txt").write_text("mine\n")
    before = tree(ctx.work)
    for out, what in ((".", "is the current directory"), ("..", "holds the current directory"),
                      (str(cwd), "is the current directory")):
        expect_input_error(ctx.run("run", "--t-end", "1", "--out", out, cwd=cwd), key=f"--out {out}", text=what)
        check(tree(ctx.work) == before, f"--out {out}: something was written")
        check(not [p for p in ctx.work.rglob(".*sesi-*")], f"--out {out}: a staging folder or lock was left")


@case
def out_empty_refused(ctx):
    expect_input_error(ctx.run("run", "--t-end", "1", "--out", ""), key="--out", text="got an empty path")
    check(not any(ctx.work.iterdir()), f"something was written: {list(ctx.work.iterdir())}")
