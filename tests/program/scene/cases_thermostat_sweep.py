# The thermostat's keys in sweeps (docs/sweeps.md): thermostat.temperature, .seed, ... vary like any
# scene key; a [[vary]] perturbation's seed and thermostat.seed are separate keys. Exec'd in
# check_program.py's namespace (thermostat_scene, LANGEVIN from cases_thermostat.py).

import csv as _csv


def sweep_rows(out):
    with open(out / "sweep.csv", newline="") as f:
        return list(_csv.DictReader(f))


def sweep_run_files(out, index):
    run = out / "runs" / f"{index:04d}"
    return (run / "diagnostics.csv").read_bytes(), summary(run)


@case
def thermostat_sweep_keys(ctx):
    """thermostat.temperature x thermostat.seed: 4 runs whose settings and columns say so."""
    ctx.write("langevin.toml", thermostat_scene(LANGEVIN, "dt = 0.01\nt_end = 0.1\n"))
    sweep = ctx.write("temperatures.toml", """scene = "langevin.toml"
[[vary]]
key = "thermostat.temperature"
values = [0.5, [[0.0, 2.0], [0.1, 1.0]]]
[[vary]]
key = "thermostat.seed"
values = [1, 2]
""")
    out = ctx.work / "sweep"
    result = ctx.run("sweep", sweep, "--out", out, "-q")
    # A schedule and a number are values of different shapes: refused before anything runs.
    expect_input_error(result, text="same shape")
    check(not out.exists(), "a refused sweep wrote its directory")
    sweep.write_text(sweep.read_text().replace("values = [0.5, [[0.0, 2.0], [0.1, 1.0]]]", "values = [0.5, 1.5]"))
    result = ctx.run("sweep", sweep, "--out", out, "-q")
    expect_ok(result, "a sweep of thermostat keys")
    rows = sweep_rows(out)
    check([(r["thermostat.temperature"], r["thermostat.seed"]) for r in rows] ==
          [("0.5", "1"), ("0.5", "2"), ("1.5", "1"), ("1.5", "2")], f"rows: {rows}")
    diagnostics = []
    for index, row in enumerate(rows):
        check(row["status"] == "ok", f"run {index}: {row}")
        data, s = sweep_run_files(out, index)
        check(thermostat_settings(s) == {"kind": "langevin", "temperature": float(row["thermostat.temperature"]),
                                  "gamma": 1.0, "seed": int(row["thermostat.seed"])}, f"run {index}: {s['thermostat']}")
        diagnostics.append(data)
    check(len(set(diagnostics)) == 4, "two runs of the sweep differ in temperature or seed but not in their diagnostics")
    # A bad value is refused with the scene reader's message, naming the run.
    bad = ctx.write("bad.toml", 'scene = "langevin.toml"\n[[vary]]\nkey = "thermostat.gamma"\nvalues = [1.0, -1.0]\n')
    result = ctx.run("sweep", bad, "--out", ctx.work / "bad", "-q")
    expect_input_error(result, text="thermostat.gamma: expected a finite friction gamma > 0")


@case
def thermostat_sweep_seeds_apart(ctx):
    """A perturbation's seed draws the perturbations only; thermostat.seed keys the noise only."""
    ctx.write("langevin.toml", thermostat_scene(LANGEVIN, "dt = 0.01\nt_end = 0.1\nenergy_guard = 1.0\n"))

    def sweep(name, perturbed_key, perturb_seed, thermostat_seeds):
        path = ctx.write(name, f"""scene = "langevin.toml"
[[vary]]
key = "thermostat.seed"
values = {thermostat_seeds}
[[vary]]
key = "{perturbed_key}"
perturb = 1e-3
count = 1
seed = {perturb_seed}
""")
        out = ctx.work / name.replace(".toml", "")
        expect_ok(ctx.run("sweep", path, "--out", out, "-q"), f"sweep {name}")
        return out

    # Body 0's x perturbed with seed 5, for thermostat seeds 1 and 2: the same perturbed point (the
    # thermostat's seed draws no perturbation), other noise (the runs differ).
    a = sweep("a.toml", "bodies.0.x", 5, [1, 2])
    rows = sweep_rows(a)
    x = [[r[f"bodies.0.x.{i}"] for i in range(3)] for r in rows]
    check(x[0] == x[1], f"the perturbation depends on thermostat.seed: {x}")
    check(sweep_run_files(a, 0)[0] != sweep_run_files(a, 1)[0], "thermostat seeds 1 and 2 give the same run")
    # The energy guard's threshold (which changes no step) perturbed with seeds 5 and 6, at thermostat
    # seed 1: other perturbations, the same noise (the runs' diagnostics are equal byte for byte).
    b = sweep("b.toml", "integrator.energy_guard", 5, [1])
    c = sweep("c.toml", "integrator.energy_guard", 6, [1])
    guard_b, guard_c = sweep_rows(b)[0]["integrator.energy_guard"], sweep_rows(c)[0]["integrator.energy_guard"]
    check(guard_b != guard_c, f"perturbation seeds 5 and 6 give the same threshold {guard_b}")
    check(sweep_run_files(b, 0)[0] == sweep_run_files(c, 0)[0], "the perturbation's seed changed the thermostat's noise")
