# The [thermostat] table (issue #25; docs/scene-format.md): every bad value refused with one line
# naming the key and its line, nothing written; the method it runs with (sesi2, its default; auto
# picks it); a temperature schedule read as written; the thermostat keys in sweeps, the sweep's
# perturbation seed and the thermostat's seed apart. Exec'd in check_program.py's namespace.

THERMOSTAT_BODIES = """[space]
kind = "sphere"
dim = 2

[[bodies]]
mass = 1.0
x = [1.0, 0.0, 0.0]
v = [0.0, 0.3, 0.0]

[[bodies]]
mass = 1.0
x = [0.0, 1.0, 0.0]
v = [0.0, 0.0, 0.3]

[[potential]]
kind = "harmonic-pair"
k = 1.0
d0 = 1.0
"""

LANGEVIN = """[thermostat]
kind = "langevin"
temperature = 0.5
gamma = 1.0
seed = 3
"""


def thermostat_scene(thermostat, integrator='dt = 0.01\nt_end = 0.2\n'):
    return THERMOSTAT_BODIES + "\n[integrator]\n" + integrator + "\n" + thermostat


def thermostat_settings(s):
    """summary.json's thermostat settings (the object also holds the run's thermostat results)."""
    return {k: v for k, v in s["thermostat"].items() if k in ("kind", "temperature", "gamma", "tau", "chain", "seed")}


def line_of(text, marker):
    """The 1-based line of the first line that contains marker."""
    for number, line in enumerate(text.splitlines(), start=1):
        if marker in line:
            return number
    raise Failure(f"no line with {marker!r} in the scene")


# (name, [thermostat] table, key, marker of the line sesi must name, text in the message)
BAD_THERMOSTATS = [
    ("kind missing", '[thermostat]\ntemperature = 1.0\ngamma = 1.0\n', "thermostat.kind", "[thermostat]",
     "missing required key"),
    ("kind unknown", '[thermostat]\nkind = "langevine"\ntemperature = 1.0\ngamma = 1.0\n', "thermostat.kind",
     'kind = "langevine"', "did you mean 'langevin'"),
    ("kind not a string", '[thermostat]\nkind = 1\ntemperature = 1.0\n', "thermostat.kind", "kind = 1", "got an integer"),
    ("temperature missing", '[thermostat]\nkind = "langevin"\ngamma = 1.0\n', "thermostat.temperature", "[thermostat]",
     "missing required key"),
    ("temperature negative", '[thermostat]\nkind = "langevin"\ntemperature = -1.0\ngamma = 1.0\n',
     "thermostat.temperature", "temperature =", "kT >= 0"),
    ("temperature nan", '[thermostat]\nkind = "csvr"\ntemperature = nan\ntau = 1.0\n', "thermostat.temperature",
     "temperature =", "finite temperature"),
    ("temperature a string", '[thermostat]\nkind = "langevin"\ntemperature = "300K"\ngamma = 1.0\n',
     "thermostat.temperature", "temperature =", "got a string"),
    ("nose-hoover at zero", '[thermostat]\nkind = "nose-hoover"\ntemperature = 0.0\ntau = 1.0\n',
     "thermostat.temperature", "temperature =", "kT > 0"),
    ("schedule empty", '[thermostat]\nkind = "langevin"\ntemperature = []\ngamma = 1.0\n', "thermostat.temperature",
     "temperature =", "empty"),
    ("schedule times not increasing", '[thermostat]\nkind = "langevin"\ngamma = 1.0\ntemperature = [[0.0, 1.0], [0.0, 2.0]]\n',
     "thermostat.temperature[2][1]", "temperature =", "increase strictly"),
    ("schedule not pairs", '[thermostat]\nkind = "brownian"\ngamma = 1.0\ntemperature = [[0.0, 1.0, 2.0]]\n',
     "thermostat.temperature[1]", "temperature =", "a pair [t, T]"),
    ("schedule negative", '[thermostat]\nkind = "csvr"\ntau = 1.0\ntemperature = [[0.0, 1.0],\n  [5.0, -1.0]]\n',
     "thermostat.temperature[2][2]", "[5.0, -1.0]", "kT >= 0"),
    ("schedule nose-hoover to zero", '[thermostat]\nkind = "nose-hoover"\ntau = 1.0\ntemperature = [[0.0, 1.0], [5.0, 0.0]]\n',
     "thermostat.temperature[2][2]", "temperature =", "kT > 0"),
    ("schedule time infinite", '[thermostat]\nkind = "langevin"\ngamma = 1.0\ntemperature = [[0.0, 1.0], [inf, 2.0]]\n',
     "thermostat.temperature[2][1]", "temperature =", "finite time"),
    ("gamma missing", '[thermostat]\nkind = "langevin"\ntemperature = 1.0\n', "thermostat.gamma", "[thermostat]",
     "missing required key"),
    ("gamma zero", '[thermostat]\nkind = "langevin"\ntemperature = 1.0\ngamma = 0.0\n', "thermostat.gamma", "gamma =",
     "gamma > 0"),
    ("gamma infinite", '[thermostat]\nkind = "brownian"\ntemperature = 1.0\ngamma = inf\n', "thermostat.gamma",
     "gamma =", "finite"),
    ("tau missing", '[thermostat]\nkind = "csvr"\ntemperature = 1.0\n', "thermostat.tau", "[thermostat]",
     "missing required key"),
    ("tau negative", '[thermostat]\nkind = "nose-hoover"\ntemperature = 1.0\ntau = -0.5\n', "thermostat.tau", "tau =",
     "tau > 0"),
    ("chain zero", '[thermostat]\nkind = "nose-hoover"\ntemperature = 1.0\ntau = 1.0\nchain = 0\n', "thermostat.chain",
     "chain =", "from 1 to 100"),
    ("chain too long", '[thermostat]\nkind = "nose-hoover"\ntemperature = 1.0\ntau = 1.0\nchain = 101\n',
     "thermostat.chain", "chain =", "from 1 to 100"),
    ("chain a float", '[thermostat]\nkind = "nose-hoover"\ntemperature = 1.0\ntau = 1.0\nchain = 2.5\n',
     "thermostat.chain", "chain =", "got a float"),
    ("seed negative", '[thermostat]\nkind = "langevin"\ntemperature = 1.0\ngamma = 1.0\nseed = -1\n', "thermostat.seed",
     "seed =", "from 0 to 2^63 - 1"),
    ("seed a float", '[thermostat]\nkind = "csvr"\ntemperature = 1.0\ntau = 1.0\nseed = 1.5\n', "thermostat.seed",
     "seed =", "got a float"),
    ("gamma with nose-hoover", '[thermostat]\nkind = "nose-hoover"\ntemperature = 1.0\ntau = 1.0\ngamma = 1.0\n',
     "thermostat.gamma", "gamma =", "not a key of a nose-hoover thermostat (gamma goes with 'langevin' or 'brownian'"),
    ("seed with nose-hoover", '[thermostat]\nkind = "nose-hoover"\ntemperature = 1.0\ntau = 1.0\nseed = 2\n',
     "thermostat.seed", "seed =", "not a key of a nose-hoover thermostat"),
    ("tau with langevin", '[thermostat]\nkind = "langevin"\ntemperature = 1.0\ngamma = 1.0\ntau = 1.0\n',
     "thermostat.tau", "tau =", "not a key of a langevin thermostat"),
    ("chain with csvr", '[thermostat]\nkind = "csvr"\ntemperature = 1.0\ntau = 1.0\nchain = 3\n',
     "thermostat.chain", "chain =", "goes with 'nose-hoover'"),
    ("unknown key", '[thermostat]\nkind = "langevin"\ntemprature = 1.0\ngamma = 1.0\n', "thermostat.temprature",
     "temprature =", "did you mean 'temperature'"),
]


@case
def thermostat_bad_values(ctx):
    """Each bad [thermostat] value: exit 2, one line naming the file, line and key, nothing written."""
    out = ctx.work / "out"
    before = earlier_outputs(out)
    for name, table, key, marker, text in BAD_THERMOSTATS:
        scene = thermostat_scene(table)
        path = ctx.write("bad-thermostat.toml", scene)
        result = ctx.run("run", path, "--out", out)
        try:
            expect_input_error(result, file=path, line=line_of(scene, marker), key=key, text=text)
        except Failure as e:
            raise Failure(f"{name}: {e}")
        expect_untouched(out, before)
    # Not a table.
    scene = "thermostat = 1.0\n" + thermostat_scene("")
    path = ctx.write("bad-thermostat.toml", scene)
    expect_input_error(ctx.run("run", path, "--out", out), file=path, line=1, key="thermostat", text="expected a table")
    expect_untouched(out, before)


# (name, [integrator] lines, [thermostat] table, text)
BAD_METHODS = [
    ("a composition of higher order", 'method = "sesi4"\ndt = 0.01\nt_end = 0.2\n', LANGEVIN, 'got "sesi4"'),
    ("a geodesic method", 'method = "geodesic2"\ndt = 0.01\nt_end = 0.2\n', LANGEVIN, 'runs with method "sesi2"'),
    ("a processed method", 'method = "sesi6-processed"\ndt = 0.01\nt_end = 0.2\n', LANGEVIN, 'runs with method "sesi2"'),
    ("auto with brownian", 'method = "auto"\ntolerance = 1e-6\nt_end = 0.2\n',
     '[thermostat]\nkind = "brownian"\ntemperature = 1.0\ngamma = 2.0\n', "brownian thermostat's overdamped step"),
]


@case
def thermostat_method_refused(ctx):
    """A thermostat runs with sesi2 (or auto): any other method named in the scene is refused at its line."""
    out = ctx.work / "out"
    before = earlier_outputs(out)
    for name, integrator, table, text in BAD_METHODS:
        scene = thermostat_scene(table, integrator)
        path = ctx.write("bad-method.toml", scene)
        try:
            expect_input_error(ctx.run("run", path, "--out", out), file=path, line=line_of(scene, "method ="),
                               key="integrator.method", text=text)
        except Failure as e:
            raise Failure(f"{name}: {e}")
        expect_untouched(out, before)


@case
def thermostat_default_method_and_summary(ctx):
    """With a [thermostat] and no method the scene runs sesi2; summary.json holds the settings."""
    path = ctx.write("langevin.toml", thermostat_scene(LANGEVIN))
    out = ctx.work / "langevin"
    result = ctx.run("run", path, "--out", out)
    expect_ok(result, "a langevin scene")
    s = summary(out)
    check(s["method"] == "sesi2", f"method {s['method']}, expected sesi2 (a thermostat's default)")
    check(thermostat_settings(s) == {"kind": "langevin", "temperature": 0.5, "gamma": 1.0, "seed": 3},
          f"summary thermostat: {s.get('thermostat')}")
    check("thermostat langevin, kT = 0.5, gamma = 1, seed 3" in result.stdout, f"report: {result.stdout!r}")
    # Every kind's keys, its defaults (chain 3, seed 0) filled in.
    for table, expected in [
        ('[thermostat]\nkind = "nose-hoover"\ntemperature = 2\ntau = 0.5\n',
         {"kind": "nose-hoover", "temperature": 2.0, "tau": 0.5, "chain": 3}),
        ('[thermostat]\nkind = "csvr"\ntemperature = 1.5\ntau = 0.25\n',
         {"kind": "csvr", "temperature": 1.5, "tau": 0.25, "seed": 0}),
        ('[thermostat]\nkind = "brownian"\ntemperature = 0.0\ngamma = 4.0\nseed = 9223372036854775807\n',
         {"kind": "brownian", "temperature": 0.0, "gamma": 4.0, "seed": 9223372036854775807}),
    ]:
        path = ctx.write("kind.toml", thermostat_scene(table, 'method = "sesi2"\ndt = 0.01\nt_end = 0.05\n'))
        out = ctx.work / f"kind-{expected['kind']}"
        expect_ok(ctx.run("run", path, "--out", out, "-q"), f"a {expected['kind']} scene")
        s = summary(out)
        check(thermostat_settings(s) == expected and s["method"] == "sesi2", f"{expected['kind']}: {s.get('thermostat')}")
    # Without a thermostat nothing changes: no "thermostat" in summary.json.
    path = ctx.write("nve.toml", thermostat_scene(""))
    expect_ok(ctx.run("run", path, "--out", ctx.work / "nve", "-q"), "NVE")
    check("thermostat" not in summary(ctx.work / "nve"), "an NVE run's summary names a thermostat")


@case
def thermostat_schedule_parsed(ctx):
    """A schedule is kept knot for knot; the temperature column follows it, linear between knots."""
    knots = [[0.0, 2.0], [0.05, 0.5], [0.15, 1.25]]
    table = ('[thermostat]\nkind = "langevin"\ngamma = 2.0\nseed = 1\n'
             'temperature = [[0.0, 2.0], [0.05, 0.5],\n  [0.15, 1.25]]\n')
    path = ctx.write("schedule.toml", thermostat_scene(table))
    out = ctx.work / "schedule"
    expect_ok(ctx.run("run", path, "--out", out, "-q"), "a scheduled run")
    s = summary(out)
    check(s["thermostat"]["temperature"] == knots, f"schedule {s['thermostat']['temperature']}, expected {knots}")
    header, rows = read_csv(out / "diagnostics.csv")
    check("temperature" in header, f"diagnostics.csv has no temperature column: {header}")
    column = header.index("temperature")

    def expected(t):  # ThermostatSpec::temperature_at: constant outside the knots, linear between
        if t <= knots[0][0]:
            return knots[0][1]
        if t >= knots[-1][0]:
            return knots[-1][1]
        k = next(i for i in range(1, len(knots)) if knots[i][0] >= t)
        (t0, T0), (t1, T1) = knots[k - 1], knots[k]
        return T0 + (T1 - T0) * ((t - t0) / (t1 - t0))
    for row in rows:
        # The row's time is printed to 17 digits: its kT is that of the same double, up to the
        # interpolation's rounding (a few ulp of kT <= 2: 1e-15).
        check(abs(row[column] - expected(row[0])) <= 1e-15, f"t = {row[0]}: temperature {row[column]}, "
                                                            f"expected {expected(row[0])}")
    check(len(rows) == 21 and rows[0][column] == 2.0 and rows[-1][column] == 1.25, f"{len(rows)} rows")


@case
def thermostat_auto_picks_sesi2(ctx):
    """method auto with a thermostat tries sesi2 alone (pilots without the thermostat) and says why."""
    path = ctx.write("auto.toml", thermostat_scene(LANGEVIN, 'method = "auto"\ntolerance = 1e-6\nt_end = 1.0\n'))
    out = ctx.work / "auto"
    result = ctx.run("run", path, "--out", out)
    expect_ok(result, "auto with a langevin thermostat")
    s = summary(out)
    a = s["auto"]
    check(s["method"] == "sesi2" and [c["method"] for c in a["candidates"]] == ["sesi2"], f"auto: {a}")
    check(a["reason"].startswith("sesi2 at dt ") and "thermostat runs with sesi2 only" in a["reason"], a["reason"])
    check(0 < s["dt"] <= 1.0, f"dt {s['dt']}")
    check("sesi: warning" not in result.stderr, f"stderr: {result.stderr!r}")
