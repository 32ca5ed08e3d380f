# `sesi run --list-methods [--json]` (src/scene/method_list.hpp): the machine-readable method list
# that tools and tests read instead of --help. Exec'd in check_program.py's namespace.

LIST_FIELDS = {"name": str, "order": int, "family": str, "processed": bool, "stages": int,
               "output_stages": int, "spaces": list, "about": str}
SPACE_SCENES = {"sphere": "sphere-two-body-xv.toml", "hyperbolic": "hyperbolic-kepler-xv.toml",
                "euclidean": "euclidean-figure-eight-xv.toml"}


def listed_methods(ctx):
    result = ctx.run("run", "--list-methods", "--json")
    expect_ok(result, "sesi run --list-methods --json")
    return json.loads(result.stdout)["methods"]


@case
def list_methods_text_and_json(ctx):
    """One name per line, the same names in the JSON list, each with every field, and the same
    methods, in the same order, as --help's METHODS (both come from the one registry)."""
    text = ctx.run("run", "--list-methods")
    expect_ok(text, "sesi run --list-methods")
    names = text.stdout.splitlines()
    check(names and all(n and n == n.strip() and " " not in n for n in names), f"not one name a line: {names}")
    methods = listed_methods(ctx)
    check([m["name"] for m in methods] == names, f"--json names {[m['name'] for m in methods]} != {names}")
    check(len(set(names)) == len(names), f"a name twice: {names}")
    for m in methods:
        check(set(m) == set(LIST_FIELDS), f"{m.get('name')}: fields {sorted(m)}")
        for field, kind in LIST_FIELDS.items():
            check(type(m[field]) is kind, f"{m['name']}: {field} = {m[field]!r}, not {kind.__name__}")
        check(m["family"] in ("chart", "processed", "geodesic", "reference"), f"{m['name']}: family {m['family']}")
        check(m["stages"] >= 1 and m["order"] >= 2 and m["order"] % 2 == 0, f"{m['name']}: {m}")
        # A processed method reads its state through the post-processor: extra evaluations there only.
        check(m["processed"] == (m["output_stages"] > 0), f"{m['name']}: processed {m['processed']}, "
              f"output_stages {m['output_stages']}")
        check(m["spaces"] and set(m["spaces"]) <= set(SPACE_SCENES), f"{m['name']}: spaces {m['spaces']}")
        check(f"({m['stages']} stage" in m["about"] or f"; {m['stages']} stage" in m["about"],
              f"{m['name']}: {m['stages']} stages, about says {m['about']!r}")
        check(not m["output_stages"] or f"; {m['output_stages']} more per output" in m["about"],
              f"{m['name']}: output_stages {m['output_stages']}, about says {m['about']!r}")
        if m["name"] in METHODS:  # the driver's own table of the chart methods' orders
            check(m["order"] == METHODS[m["name"]], f"{m['name']}: order {m['order']}, expected {METHODS[m['name']]}")
    check(set(METHODS) <= set(names), f"not listed: {sorted(set(METHODS) - set(names))}")
    helped = ctx.run("run", "--help").stdout.split("\nMETHODS")[1].split("\n  auto ")[0].splitlines()[1:]
    check([line.split()[0] for line in helped] == names, f"--help's METHODS {helped} != {names}")


@case
def list_methods_spaces_hold(ctx):
    """Each method runs on every space it lists (exit 0) and is refused on the others (exit 2)."""
    for m in listed_methods(ctx):
        for space, scene in SPACE_SCENES.items():
            out = ctx.work / f"{m['name']}-{space}"
            result = ctx.run("run", ctx.scene(scene), "--method", m["name"], "--dt", "0.01", "--t-end", "0.05",
                             "--out", out, "-q")
            if space in m["spaces"]:
                expect_ok(result, f"{m['name']} on {space}")
                check(summary(out)["method"] == m["name"], f"{m['name']} on {space}: {summary(out)['method']}")
            else:
                expect_input_error(result, text=f"method '{m['name']}'")
                check(not out.exists(), f"{m['name']} on {space}: {out} written")
                expect_no_staging_left(out)


@case
def list_methods_bad_use(ctx):
    """--json without --list-methods, or --list-methods with a scene or a run option: exit 2, one
    line naming the option, nothing written."""
    out = ctx.work / "out"
    for args, key in [(["--json"], "--json"),
                      (["--list-methods", ctx.scene("paper.toml")], "--list-methods"),
                      (["--list-methods", "--method", "sesi4"], "--list-methods"),
                      (["--list-methods", "--json", "--out", out], "--list-methods")]:
        result = ctx.run("run", *args, cwd=ctx.work)
        expect_input_error(result, key=key)
        check(not out.exists() and not (ctx.work / "sesi-out").exists(), f"{args}: an output directory was made")
