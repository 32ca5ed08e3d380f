# The scene reader's limits (issue #12, src/scene/scene_limits.cpp): size, parts of a dotted key or a
# table header, nesting of arrays and inline tables, checked before toml++ sees the text. A dotted
# key of 35,000 parts (an 80 KB file) used to kill sesi with SIGSEGV (a stack overflow in toml++).
# Exec'd in check_program.py's namespace (case, check, expect_input_error, expect_ok, ...).

def _limits_scene(ctx):
    """A valid scene (the two-body example) to put a bad key or header into."""
    return ctx.scene("sphere-two-body-qp.toml").read_text()


def _dotted(n):
    return ".".join(["a"] * n)


def _expect_limit(ctx, name, text, line, message):
    """sesi refuses text (written to name) with exit 2, one line naming the file and line, and the
    message; it does not crash and writes nothing."""
    path = ctx.write(name, text)
    out = ctx.work / "out"
    before = earlier_outputs(out)
    result = ctx.run("run", path, "--out", out)
    check(result.returncode >= 0, f"killed by signal {-result.returncode}: {result.stderr!r}")
    expect_input_error(result, file=path, line=line, text=message)
    expect_untouched(out, before)


@case
def reader_limits_deep_dotted_key(ctx):
    # The input of the issue: line 2 holds a key of 35001 parts.
    text = "# issue 12\n" + _dotted(35001) + " = 1\n" + _limits_scene(ctx)
    _expect_limit(ctx, "deep-key.toml", text, 2, "key has 35001 dotted parts; at most 64 are allowed")


@case
def reader_limits_deep_table_header(ctx):
    scene = _limits_scene(ctx)
    line = scene.count("\n") + 1
    _expect_limit(ctx, "deep-header.toml", scene + "[" + _dotted(35001) + "]\nb = 1\n", line,
                  "table header has 35001 dotted parts; at most 64 are allowed")


@case
def reader_limits_deep_array_of_tables_header(ctx):
    _expect_limit(ctx, "deep-aot.toml", "[[" + _dotted(35001) + "]]\n" + _limits_scene(ctx), 1,
                  "table header has 35001 dotted parts; at most 64 are allowed")


@case
def reader_limits_deep_arrays(ctx):
    text = _limits_scene(ctx).replace("p = [0.0, 0.4]", "p = " + "[" * 40000 + "]" * 40000, 1)
    line = text.splitlines().index("p = " + "[" * 40000 + "]" * 40000) + 1
    _expect_limit(ctx, "deep-arrays.toml", text, line,
                  "arrays and inline tables are nested 65 deep; at most 64 levels are allowed")


@case
def reader_limits_deep_inline_tables(ctx):
    text = "a = " + "{a=" * 40000 + "1" + "}" * 40000 + "\n" + _limits_scene(ctx)
    _expect_limit(ctx, "deep-inline.toml", text, 1,
                  "arrays and inline tables are nested 65 deep; at most 64 levels are allowed")


@case
def reader_limits_deep_inline_dotted_keys(ctx):
    # Each limit alone kept, the levels add up: 64-part keys in inline tables nested 60 deep.
    text = "a = " + ("{" + _dotted(64) + "=") * 60 + "1" + "}" * 60 + "\n" + _limits_scene(ctx)
    _expect_limit(ctx, "deep-inline-dotted.toml", text, 1,
                  "a value is nested 129 levels deep (table header, dotted keys, arrays and inline "
                  "tables together); at most 128 are allowed")


@case
def reader_limits_at_the_limits(ctx):
    # Exactly at each limit the scene reaches the reader, which names the unknown key instead.
    scene = _limits_scene(ctx)
    for name, text in [("key-64.toml", _dotted(64) + " = 1\n" + scene),
                       ("header-64.toml", "[" + _dotted(64) + "]\n" + scene),
                       ("nest-64.toml", "a = " + "[" * 64 + "]" * 64 + "\n" + scene),
                       ("inline-64.toml", "a = " + "{a=" * 63 + "{}" + "}" * 63 + "\n" + scene)]:
        path = ctx.write(name, text)
        result = ctx.run("run", path, "--out", ctx.work / "out")
        expect_input_error(result, file=path, line=1, key="a", text="unknown key")
        check("allowed" not in result.stderr, f"{name}: refused by a limit: {result.stderr!r}")


@case
def reader_limits_strings_and_comments_do_not_count(ctx):
    # Brackets, braces, dots and quotes inside strings and comments are not structure: a valid
    # scene full of them runs.
    noise = "[{" * 200 + _dotted(200) + "]}" * 3
    scene = _limits_scene(ctx).replace('name = "sphere-two-body"',
                                       'name = "' + noise + '\\"\'\\\\"  # ' + noise, 1)
    scene = scene.replace("q = [1.2, 0.0]", "q = [  # " + noise + " '''\"\n  1.2,\n  0.0]", 1)
    path = ctx.write("noisy.toml", scene)
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--t-end", "0.01", "--out", out, "-q"), "noisy scene")
    check(summary(out)["complete"], "the noisy scene did not complete")


@case
def reader_limits_file_size(ctx):
    # A sparse file one byte over 1 GiB is refused from its size, before it is read.
    path = ctx.work / "huge.toml"
    with open(path, "wb") as f:
        f.truncate((1 << 30) + 1)
    start = time.monotonic()
    result = ctx.run("run", path, "--out", ctx.work / "out")
    expect_input_error(result, file=path, text="more than 1073741824 bytes (1 GiB)")
    check(time.monotonic() - start < 30, "the size limit took long: was the file read?")
    path.unlink()


@case
def reader_limits_fuzz_regressions(ctx):
    # The fuzz corpus's regression inputs (fuzz/regressions, `make fuzz` seeds): each one exits 2
    # with one line, none crashes.
    inputs = sorted((ctx.source / "fuzz" / "regressions").glob("*.toml"))
    check(len(inputs) >= 5, f"fuzz/regressions holds {len(inputs)} inputs")
    for path in inputs:
        result = ctx.run("run", path, "--out", ctx.work / "out")
        check(result.returncode == 2, f"{path.name}: exit status {result.returncode}: {result.stderr!r}")
        expect_input_error(result, file=path)


# ---- overflow says overflow (issue #12) ---------------------------------------------------------

OVERFLOW_RUN = """name = "overflow"
# A harmonic pair stepped far beyond its stability limit (w dt = 14 > 2): the state grows by about
# 200x a step and overflows to inf, with the energy guard off so that nothing stops it before.
[space]
kind = "euclidean"
dim = 1
[[bodies]]
mass = 1.0
q = [0.5]
p = [0.0]
[[bodies]]
mass = 1.0
q = [-0.5]
p = [0.0]
[[potential]]
kind = "harmonic-pair"
k = 1.0
[integrator]
method = "sesi2"
dt = 10.0
t_end = 10000.0
energy_guard = false
"""


@case
def run_overflow_says_overflow(ctx):
    result = ctx.run("run", ctx.write("overflow.toml", OVERFLOW_RUN), "--out", ctx.work / "out")
    err = result.stderr
    check(result.returncode == 3, f"exit status {result.returncode}, expected 3: {err!r}")
    check(err.count("\n") == 1 and "non-finite" in err, f"expected one line: {err!r}")
    check("overflowed to +-inf" in err and "NaN" not in err, f"the message does not say overflow: {err!r}")


@case
def run_nan_says_nan(ctx):
    # check_program.py's BLOWUP: the chord-well's square root of a negative number.
    result = ctx.run("run", ctx.write("blowup.toml", BLOWUP), "--out", ctx.work / "out")
    err = result.stderr
    check(result.returncode == 3, f"exit status {result.returncode}, expected 3: {err!r}")
    check("became NaN" in err and "overflow" not in err, f"the message does not say NaN: {err!r}")


# ---- messages quote at most 80 bytes of the input (issue #24) -----------------------------------

import re  # noqa: E402 (this file is exec'd in check_program.py's namespace)

_LONG = 10_000_000  # the 10 MB


def _long_input_cases(scene):
    """(file name, scene text, the quoted piece's first 80 bytes, its size in the message): a
    10 MB key, string or table name wherever a message quotes one."""
    k = "k" * _LONG
    return [
        ("long-key.toml", k + " = 1\n" + scene, "k" * 80, _LONG),
        ("long-space-kind.toml", scene.replace('kind = "sphere"', f'kind = "{k}"', 1), "k" * 80, _LONG),
        ("long-name.toml", scene.replace('name = "sphere-two-body"', f'name = "/{k}"', 1), "/" + "k" * 79, _LONG + 1),
        ("long-potential-kind.toml", scene.replace('kind = "cotangent-gravity"', f'kind = "{k}"', 1), "k" * 80, _LONG),
        ("long-method.toml", scene.replace('method = "sesi4"', f'method = "{k}"', 1), "k" * 80, _LONG),
        # toml++'s own message quotes the table's name, cut by toml++ to some 500 bytes
        ("long-table-twice.toml", f"[{k}]\n[{k}]\n" + scene, "k" * 80, None),
    ]


@case
def reader_limits_long_input_cut(ctx):
    # stderr is the message for a 10-byte piece, the piece now 80 bytes and "... (N bytes)".
    scene = _limits_scene(ctx)
    for name, text, head, size in _long_input_cases(scene):
        short = ctx.run("run", ctx.write(name, text.replace("k" * _LONG, "k" * 10)), "--out", ctx.work / "out")
        path = ctx.write(name, text)
        result = ctx.run("run", path, "--out", ctx.work / "out")
        err = result.stderr
        shown = err if len(err) < 1000 else err[:300] + f"... ({len(err)} bytes)"
        check(short.returncode == 2 and len(err) <= len(short.stderr) + 80 + 21 - 10,
              f"{name}: {len(err)} bytes on stderr, {len(short.stderr)} for a 10-byte piece: {shown!r}")
        expect_input_error(result, file=path)
        cut = re.search(re.escape(head) + r"\.\.\. \((\d+) bytes\)", err)
        check(cut and (size is None or int(cut.group(1)) == size),
              f"{name}: the quoted piece is not cut to 80 bytes and its size ({size}): {shown!r}")
        check(not (ctx.work / "out").exists(), f"{name}: outputs were written")
        path.unlink()
