# Where the outputs go (src/outputs): what --out may name, and a run replacing an earlier run's
# outputs. More on the output directory in cases_output_dir.py; H5MD in check_h5md.py.
# Exec'd in check_program.py's namespace: case, check, earlier_outputs, snapshot, ... come from there.


# ---- the output directory ----------------------------------------------------------------------

@case
def out_parent_is_a_file(ctx):
    blocker = ctx.write("blocker", "a file where a directory should be\n")
    result = ctx.run("run", "--t-end", "1", "--out", blocker / "sub")
    expect_input_error(result, key=f"--out {blocker / 'sub'}", text="cannot create the parent directory")
    check(blocker.read_text() == "a file where a directory should be\n", "the blocking file changed")


@case
def out_is_a_file(ctx):
    target = ctx.write("target", "not a directory\n")
    result = ctx.run("run", "--t-end", "1", "--out", target)
    expect_input_error(result, key=f"--out {target}", text="not a directory")
    check(target.read_text() == "not a directory\n", "the file changed")


@case
def out_holds_other_files(ctx):
    out = ctx.work / "out"
    earlier_outputs(out)
    (out / "notes.txt").write_text("mine\n")
    before = snapshot(out)
    result = ctx.run("run", "--t-end", "1", "--out", out)
    expect_input_error(result, key=f"--out {out}", text="'notes.txt', which sesi did not write")
    expect_untouched(out, before)


@case
def out_unwritable(ctx):
    if os.geteuid() == 0:
        # Root ignores directory permissions, but not sysfs's: nothing may be created there.
        out = pathlib.Path("/sys/sesi-out-test")
        if not pathlib.Path("/sys").is_dir() or out.exists():
            raise Skip("no sysfs to stand for an unwritable directory")
        result = ctx.run("run", "--t-end", "1", "--out", out)
        expect_input_error(result, key=f"--out {out}", text="cannot write")
        check(not out.exists(), f"{out} was created")
        return
    parent = ctx.work / "locked"
    parent.mkdir()
    out = parent / "out"
    before = earlier_outputs(out)
    parent.chmod(0o555)
    try:
        result = ctx.run("run", "--t-end", "1", "--out", out)
    finally:
        parent.chmod(0o755)
    expect_input_error(result, key=f"--out {out}", text="cannot write")
    expect_untouched(out, before)


@case
def replaces_earlier_outputs(ctx):
    out = ctx.work / "out"
    earlier_outputs(out)
    expect_ok(ctx.run("run", "--t-end", "1", "--out", out, "-q"), "sesi run")
    check(summary(out)["complete"] is True, "summary not replaced")
    check(not (out / "plot.png").exists(), "the earlier run's files should go with it")
    expect_no_staging_left(out)
