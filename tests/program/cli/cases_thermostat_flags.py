# `sesi run --temperature KT --seed N` (issue #25; docs/scene-format.md, "Thermostat"): they change
# the scene's [thermostat] and need one; bad values and a refused method are one line, exit 2,
# nothing written. Uses scene/cases_thermostat.py's scenes (thermostat_scene, LANGEVIN: the case files
# share check_program.py's namespace).


@case
def thermostat_flags_refused(ctx):
    """--temperature/--seed without a [thermostat], out of range, --seed for nose-hoover, --method not sesi2."""
    nve = ctx.write("nve.toml", thermostat_scene(""))
    langevin = ctx.write("langevin.toml", thermostat_scene(LANGEVIN))
    nose = ctx.write("nose.toml", thermostat_scene('[thermostat]\nkind = "nose-hoover"\ntemperature = 1.0\ntau = 0.5\n'))
    brownian = ctx.write("brownian.toml", thermostat_scene('[thermostat]\nkind = "brownian"\ntemperature = 1.0\ngamma = 2.0\n'))
    out = ctx.work / "out"
    before = earlier_outputs(out)
    for scene, args, key, text in [
        (nve, ["--temperature", "1.0"], "--temperature", "no [thermostat] table"),
        (nve, ["--seed", "3"], "--seed", "no [thermostat] table"),
        (langevin, ["--temperature", "-0.5"], "--temperature", "kT >= 0"),
        (langevin, ["--temperature", "inf"], "--temperature", "finite temperature"),
        (nose, ["--temperature", "0"], "--temperature", "kT > 0"),
        (langevin, ["--seed", "-1"], "--seed", "from 0 to 2^63 - 1"),
        (nose, ["--seed", "4"], "--seed", "no noise"),
        (langevin, ["--method", "sesi4"], "--method", 'runs with method "sesi2"'),
        (langevin, ["--method", "geodesic2"], "--method", 'runs with method "sesi2"'),
        (brownian, ["--tolerance", "1e-6"], "--tolerance", "brownian thermostat's overdamped step"),
    ]:
        result = ctx.run("run", scene, *args, "--out", out)
        try:
            expect_input_error(result, key=key, text=text)
        except Failure as e:
            raise Failure(f"{scene.name} {' '.join(args)}: {e}")
        expect_untouched(out, before)
    # Not a number: the argument parser's one line.
    for args in (["--seed", "x"], ["--seed", "18446744073709551616"], ["--temperature", "warm"]):
        result = ctx.run("run", langevin, *args, "--out", out)
        expect_input_error(result, text=args[0])
        expect_untouched(out, before)


@case
def thermostat_flags_replace_the_scene(ctx):
    """--temperature replaces the scene's temperature (a schedule too), --seed its seed: the run equals
    that of a scene file giving them, and another seed gives another run."""
    def table(temperature, seed):
        return f'[thermostat]\nkind = "langevin"\ngamma = 1.0\nseed = {seed}\ntemperature = {temperature}\n'
    scheduled = ctx.write("scheduled.toml", thermostat_scene(table("[[0.0, 3.0], [0.1, 0.2]]", 3)))
    given = ctx.write("given.toml", thermostat_scene(table("0.75", 11)))
    runs = {}
    for name, scene, args in [("flags", scheduled, ["--temperature", "0.75", "--seed", "11"]),
                              ("file", given, []), ("seed12", scheduled, ["--temperature", "0.75", "--seed", "12"])]:
        out = ctx.work / name
        result = ctx.run("run", scene, *args, "--out", out)
        expect_ok(result, f"{name}: sesi run {' '.join(args)}")
        s = summary(out)
        check(thermostat_settings(s) == {"kind": "langevin", "temperature": 0.75, "gamma": 1.0,
                                  "seed": 12 if name == "seed12" else 11}, f"{name}: {s['thermostat']}")
        runs[name] = {f: (out / f).read_bytes() for f in ("trajectory.csv", "diagnostics.csv")}
    check(runs["flags"] == runs["file"], "--temperature 0.75 --seed 11 differs from a scene file that says so")
    check(runs["flags"]["trajectory.csv"] != runs["seed12"]["trajectory.csv"],
          "--seed 12 gives the same trajectory as --seed 11: the seed does not key the noise")
