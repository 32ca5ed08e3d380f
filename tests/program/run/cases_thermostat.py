# Thermostatted runs in the program (issue #25; docs/thermostats.md): the integrator, the run loop,
# diagnostics.csv's thermostat columns, the energy guard on the conserved quantity, checkpoints.
# Exec'd inside check_program.py: its helpers (case, check, Context, ...) and those of the other
# run/ case files (threads_sphere_scene, expect_same_files, expect_same_outputs, harmonic_scene,
# expect_run_failure, stop_default_run) are in scope.

import random

THERMOSTAT_KINDS = ["langevin", "nose-hoover", "csvr", "brownian"]
THERMOSTAT_COLUMNS = ["temperature", "kinetic_temperature", "configurational_temperature", "heat", "conserved"]


def thermostat_table(kind, temperature="1.0", gamma="1.0", tau="0.5", seed=7):
    """A [thermostat] table of kind with the keys it takes."""
    lines = ["[thermostat]", f'kind = "{kind}"', f"temperature = {temperature}"]
    if kind in ("langevin", "brownian"):
        lines.append(f"gamma = {gamma}")
    if kind in ("nose-hoover", "csvr"):
        lines.append(f"tau = {tau}")
    if kind != "nose-hoover":
        lines.append(f"seed = {seed}")
    return "\n".join(lines) + "\n"


def thermostat_lj_scene(kind, t_end="0.1", dt="0.005", output_every=5):
    """600 Lennard-Jones bodies on S^2 (threads engage from 512) at kT ~ 1, thermostatted at kT = 1.
    Brownian with gamma = 10: its engine step sqrt(2 dt / gamma) = 0.03 keeps the lattice intact."""
    text = threads_sphere_scene(600, 1.0, 11, method="sesi2", t_end=t_end, dt=dt, output_every=output_every)
    return text + thermostat_table(kind, gamma="10.0" if kind == "brownian" else "1.0")


def ideal_gas_scene(n, kT0, seed, dt, t_end, output_every, thermostat, guard=None):
    """n bodies of mass 1 on a Fibonacci lattice of S^2 (area 2 per body) with no potential, their
    velocities drawn from the Maxwell distribution at kT0: a 3-D normal of variance kT0 projected
    on the tangent plane is exactly the 2-D tangent normal of that variance."""
    rng = random.Random(seed)
    radius = math.sqrt(2.0 * n / (4.0 * math.pi))
    golden = math.pi * (3.0 - math.sqrt(5.0))
    lines = ['name = "ideal gas"', "[space]", 'kind = "sphere"', "dim = 2", f"radius = {radius!r}"]
    for i in range(n):
        z = 1.0 - (2.0 * i + 1.0) / n
        r = math.sqrt(1.0 - z * z)
        x = [radius * r * math.cos(golden * i), radius * r * math.sin(golden * i), radius * z]
        v = [rng.gauss(0.0, math.sqrt(kT0)) for _ in range(3)]
        dot = sum(a * b for a, b in zip(v, x)) / (radius * radius)
        v = [a - dot * b for a, b in zip(v, x)]
        lines += ["[[bodies]]", "mass = 1.0", f"x = [{', '.join(map(repr, x))}]", f"v = [{', '.join(map(repr, v))}]"]
    lines += ["[integrator]", 'method = "sesi2"', f"dt = {dt}", f"t_end = {t_end}", f"output_every = {output_every}"]
    if guard is not None:
        lines.append(f"energy_guard = {guard}")
    return "\n".join(lines) + "\n" + thermostat


def harmonic_cluster_scene(n_bodies, seed, dt, t_end, output_every, thermostat, check_every=None):
    """n bodies of mass 1 on E^2 in the harmonic-pair term (k = 1, d0 = 0), drawn from the canonical
    law at kT = 1: momenta N(0, 1), each coordinate N(0, 1 / N) about the centre (the internal modes'
    stiffness is k N)."""
    rng = random.Random(seed)
    spread = math.sqrt(1.0 / n_bodies)
    lines = ['name = "harmonic cluster"', "[space]", 'kind = "euclidean"', "dim = 2"]
    for _ in range(n_bodies):
        q = [rng.gauss(0.0, spread) for _ in range(2)]
        p = [rng.gauss(0.0, 1.0) for _ in range(2)]
        lines += ["[[bodies]]", "mass = 1.0", f"q = [{', '.join(map(repr, q))}]", f"p = [{', '.join(map(repr, p))}]"]
    lines += ["[[potential]]", 'kind = "harmonic-pair"', "k = 1.0", "d0 = 0.0",
              "[integrator]", 'method = "sesi2"', f"dt = {dt}", f"t_end = {t_end}", f"output_every = {output_every}"]
    if check_every is not None:
        lines.append(f"check_every = {check_every}")
    return "\n".join(lines) + "\n" + thermostat


def diagnostics_columns(out):
    header, rows = read_csv(pathlib.Path(out) / "diagnostics.csv")
    return {name: [row[k] for row in rows] for k, name in enumerate(header)}


@case
def thermostat_threads_bit_identical(ctx):
    # Every kind: --threads 1 and 2 give the same bytes in every output file (the noise is keyed by
    # (seed, step, body, component), the heat summed in body order).
    for kind in THERMOSTAT_KINDS:
        path = ctx.write(f"lj-{kind}.toml", thermostat_lj_scene(kind))
        outs = []
        for threads in (1, 2):
            out = ctx.work / f"{kind}-{threads}"
            expect_ok(ctx.run("run", path, "--threads", threads, "--out", out, "-q"), f"{kind}, --threads {threads}")
            outs.append(out)
        expect_same_files(outs[0], outs[1], f"{kind}: --threads 1 against 2")
        columns = diagnostics_columns(outs[0])
        header, _ = read_csv(outs[0] / "diagnostics.csv")
        check(header[-5:] == THERMOSTAT_COLUMNS, f"{kind}: diagnostics.csv header ends {header[-5:]}")
        check(all(math.isfinite(v) for name in THERMOSTAT_COLUMNS[:4] for v in columns[name]),
              f"{kind}: a thermostat column is not finite")
        # The thermostat acts: momenta change beyond the NVE flow's (heat != 0 after the first row).
        check(columns["heat"][0] == 0.0 and columns["heat"][-1] != 0.0, f"{kind}: heat {columns['heat']}")
        conserved = columns["conserved"]
        if kind == "brownian":
            check(all(math.isnan(v) for v in conserved), f"{kind}: conserved should be NaN (nothing is)")
        else:
            check(all(math.isfinite(v) for v in conserved), f"{kind}: conserved not finite")
        s = summary(outs[0])
        t = s["thermostat"]
        check(t["kind"] == kind and t["temperature"] == 1.0, f"{kind}: summary's thermostat {t}")
        check(t["energy_guard"].startswith("off") == (kind == "brownian"),
              f"{kind}: energy_guard {t['energy_guard']!r}")


@case
def thermostat_resume_equals_one_run(ctx):
    # Every kind: a run with checkpoints, resumed, equals one run byte for byte (the checkpoint
    # holds the thermostat's step, heat and chain; the noise is recomputed from the seed and step).
    for kind in THERMOSTAT_KINDS:
        scene = [ctx.write(f"lj-{kind}.toml", thermostat_lj_scene(kind, t_end="0.2"))]
        first, whole = ctx.work / f"first-{kind}", ctx.work / f"whole-{kind}"
        args = ["--checkpoint-every", "7", "--quiet"]
        expect_ok(ctx.run("run", *scene, "--out", whole, *args), f"{kind}: uninterrupted run")
        expect_ok(ctx.run("run", *scene, "--t-end", "0.115", "--out", first, *args), f"{kind}: first part")
        check((first / "checkpoint").read_bytes().startswith(b"sesi-checkpoint 3 "),
              f"{kind}: a thermostatted run's checkpoint is not format version 3")
        expect_ok(ctx.run("resume", first, "--t-end", "0.2", "--quiet"), f"{kind}: sesi resume")
        expect_same_outputs(first, whole, f"{kind} resumed at 0.115")


@case
def thermostat_resume_after_sigint(ctx):
    # A long Langevin run stopped by SIGINT and resumed equals one run to the same end. Its stop
    # row (between output rows) has its configurational temperature too.
    path = ctx.write("cluster.toml", harmonic_cluster_scene(20, 5, "0.01", "1.0", 1, thermostat_table("langevin")))
    out = ctx.work / "out"
    process, err = stop_default_run(ctx, out, [signal.SIGINT], path)
    check(process.returncode == 130, f"exit status {process.returncode}, expected 130: {err!r}")
    stopped_at = summary(out)["final_state"]["step"]
    stop_row = diagnostics_columns(out)["configurational_temperature"][-1]
    check(math.isfinite(stop_row) and stop_row > 0.0, f"the stop row's configurational temperature {stop_row}")
    t2 = f"{(stopped_at + 150) * 0.01:.2f}"
    expect_ok(ctx.run("resume", out, "--t-end", t2, "--quiet"), "sesi resume")
    whole = ctx.work / "whole"
    expect_ok(ctx.run("run", path, "--t-end", t2, "--output-every", "97", "--out", whole, "--quiet"), "one run")
    expect_same_outputs(out, whole, "a Langevin run resumed after SIGINT")


@case
def thermostat_langevin_mean_kinetic_temperature(ctx):
    # An ideal gas of N = 1000 bodies on S^2 (N_f = 2000) started at kT0 = 0.25 under Langevin at
    # kT = 1, gamma = 1. In equilibrium each momentum component is an exact Ornstein-Uhlenbeck
    # process, so 2K/N_f has mean kT (BAOAB's bias here is O(h^2 / R^2) ~ 1e-6), variance
    # 2 kT^2 / N_f, and rows dt_row = 1 apart correlate by rho = exp(-2 gamma dt_row) = 0.135.
    # The rows from t = 5 on (the start's offset is 0.75 exp(-2 gamma t) = 3e-5 there), M = 51 of
    # them: the mean's standard deviation is sqrt(2 / N_f / M * (1 + rho) / (1 - rho)) = 0.0051;
    # the bound is 4 of them (two-sided p = 6e-5 at this fixed seed). A thermostat that did nothing
    # would stay at 0.25; a wrong N_f (N (n + 1)) would read 0.67.
    n = 1000
    path = ctx.write("gas.toml", ideal_gas_scene(n, 0.25, 3, "0.01", "55.0", 100, thermostat_table("langevin")))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--out", out, "-q"), "Langevin ideal gas")
    columns = diagnostics_columns(out)
    kinetic = [k for t, k in zip(columns["t"], columns["kinetic_temperature"]) if t >= 5.0 - 1e-9]
    check(len(kinetic) == 51, f"{len(kinetic)} rows from t = 5")
    rho = math.exp(-2.0)
    sigma = math.sqrt(2.0 / (2 * n) / len(kinetic) * (1.0 + rho) / (1.0 - rho))
    mean = sum(kinetic) / len(kinetic)
    check(abs(mean - 1.0) < 4.0 * sigma, f"mean kinetic temperature {mean}, expected 1 within {4 * sigma}")
    start = columns["kinetic_temperature"][0]
    check(start < 0.3, f"the start's kinetic temperature {start}")
    every = columns["kinetic_temperature"]
    summary_mean = summary(out)["thermostat"]["mean_kinetic_temperature"]
    check(abs(summary_mean - sum(every) / len(every)) <= 1e-12, f"summary's mean {summary_mean}")
    # No potential: the configurational temperature is 0/0.
    check(all(math.isnan(v) for v in columns["configurational_temperature"]), "configurational temperature")


@case
def thermostat_guard_ignores_heat(ctx):
    # Heating an ideal gas of 100 bodies from kT0 = 0.25 to kT = 1 puts in ~ 75 = 3 K0, six times the
    # tight guard 0.5 (K0 + |V0|): the guard judges E + the thermostat's offset, constant up to the
    # method's error, so every kind but brownian (whose guard is off) completes.
    for kind in THERMOSTAT_KINDS:
        table = thermostat_table(kind, gamma="2.0")
        path = ctx.write(f"gas-{kind}.toml", ideal_gas_scene(100, 0.25, 4, "0.01", "5.0", 50, table, guard=0.5))
        out = ctx.work / f"out-{kind}"
        expect_ok(ctx.run("run", path, "--out", out, "-q"), f"{kind}: heating with energy_guard = 0.5")
        # With no potential E0 = K0 is the guard's scale: a guard on E itself would have stopped
        # a run whose energy rose by more than 0.5 E0; this one's rose by more than twice that.
        energy = summary(out)["energy"]
        rise = energy["final"] - energy["initial"]
        check(rise > 2 * 0.5 * energy["initial"], f"{kind}: the energy rose by {rise} only: no test of the guard")


@case
def thermostat_guard_trips_on_conserved_jump(ctx):
    # The harmonic pair of cases_run.py beyond Strang's stability limit (w dt = 2.04): the energy
    # grows by |lambda|^2 = 2.2 a step, which a weak thermostat (kT = 0.01; gamma = 0.01 takes out
    # exp(-2 gamma dt) = 0.96 a step; tau = 100) cannot hold: the guard stops it on C, as it stops
    # the NVE run (in < 30 steps, cases_run.py).
    for kind in ["langevin", "nose-hoover", "csvr"]:
        text = harmonic_scene(2.04, 200) + thermostat_table(kind, temperature="0.01", gamma="0.01", tau="100.0")
        path = ctx.write(f"stiff-{kind}.toml", text)
        out = ctx.work / f"out-{kind}"
        s = expect_run_failure(ctx, ctx.run("run", path, "--out", out), out, "energy error exceeded",
                               "conserved-quantity error exceeded", "|C - C0| = ", "energy_guard = 100")
        check(s["failure"]["step"] < 30, f"{kind}: the guard tripped late: step {s['failure']['step']}")


@case
def thermostat_schedule_quench(ctx):
    # A quench 2 -> 0.5 over t in [0, 1], held to t = 4: the temperature column is the schedule at
    # each row's t (the same double: the formula of ThermostatSpec::temperature_at), and the kinetic
    # temperature follows. Ideal gas, N = 1000, gamma = 5: from t = 2 on the offset is
    # 1.5 exp(-2 gamma (t - 1)) = 7e-5; the 11 rows 0.2 apart correlate by rho = exp(-2) and their
    # mean's deviation is 0.5 sqrt(2 / 2000 / 11 (1 + rho) / (1 - rho)) = 0.0055: bound 4 of them.
    n = 1000
    table = thermostat_table("langevin", temperature="[[0.0, 2.0], [1.0, 0.5]]", gamma="5.0")
    path = ctx.write("quench.toml", ideal_gas_scene(n, 2.0, 6, "0.01", "4.0", 20, table))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--out", out, "-q"), "quench")
    columns = diagnostics_columns(out)

    def schedule(t):
        if t <= 0.0:
            return 2.0
        if t >= 1.0:
            return 0.5
        return 2.0 + (0.5 - 2.0) * ((t - 0.0) / (1.0 - 0.0))

    for t, target in zip(columns["t"], columns["temperature"]):
        check(target == schedule(t), f"temperature {target} at t = {t}, the schedule says {schedule(t)}")
    check(columns["temperature"][0] == 2.0 and columns["temperature"][-1] == 0.5, "the quench's ends")
    late = [k for t, k in zip(columns["t"], columns["kinetic_temperature"]) if t >= 2.0 - 1e-9]
    check(len(late) == 11, f"{len(late)} rows from t = 2")
    rho = math.exp(-2.0)
    sigma = 0.5 * math.sqrt(2.0 / (2 * n) / len(late) * (1.0 + rho) / (1.0 - rho))
    mean = sum(late) / len(late)
    check(abs(mean - 0.5) < 4.0 * sigma,
          f"kinetic temperature {mean} after the quench, expected 0.5 within {4 * sigma}")
    t = summary(out)["thermostat"]["temperature"]
    check(t == [[0.0, 2.0], [1.0, 0.5]], f"summary's schedule {t}")


@case
def thermostat_resume_h5md(ctx):
    # trajectory.h5 holds the thermostat's observables too (observables/heat, ...); a resumed run
    # replays them, so its file equals one run's byte for byte.
    probe = ctx.run("run", "--t-end", "0", "--trajectory-format", "h5md", "--out", ctx.work / "probe", "-q")
    if probe.returncode != 0:
        raise Skip("sesi is built without HDF5")
    path = ctx.write("gas.toml", ideal_gas_scene(30, 1.0, 8, "0.01", "1.0", 3, thermostat_table("nose-hoover")))
    first, whole = ctx.work / "first", ctx.work / "whole"
    args = ["--checkpoint-every", "9", "--trajectory-format", "h5md", "--quiet"]
    expect_ok(ctx.run("run", path, "--out", whole, *args), "uninterrupted run")
    expect_ok(ctx.run("run", path, "--t-end", "0.47", "--out", first, *args), "first part")
    expect_ok(ctx.run("resume", first, "--t-end", "1.0", "--quiet"), "sesi resume")
    expect_same_outputs(first, whole, "a Nose-Hoover run with trajectory.h5 resumed at 0.47")
    check(b"configurational_temperature" in (whole / "trajectory.h5").read_bytes(),
          "no thermostat observables in trajectory.h5")


@case
def thermostat_configurational_temperature(ctx):
    # N = 100 bodies of mass 1 on E^2 in the harmonic-pair term V = k/2 sum_(i<j) |x_i - x_j|^2
    # (k = 1): sum_b |grad_b V|^2 = k^2 N^2 S with S = sum_b |x_b - xbar|^2, and sum_b Laplacian_b V
    # = k N (N - 1) n, so a row's configurational temperature is k N S / ((N - 1) n). The internal
    # modes (nu = (N - 1) n = 198) have stiffness k N, so in equilibrium it is kT chi^2_nu / nu:
    # mean kT, standard deviation kT sqrt(2 / nu) per row. Langevin at kT = 1 with gamma = 20, the
    # critical damping 2 omega of omega = sqrt(k N) = 10, and BAOAB samples a harmonic
    # configuration exactly (Leimkuhler and Matthews 2013; the A flows are exact on E^n). Rows 0.5
    # apart correlate by rho <= ((1 + omega 0.5) exp(-omega 0.5))^2 = 0.0016. The start is drawn
    # from the canonical law; rows from t = 2 on, M = 201: the mean's deviation is
    # sqrt(2 / nu / M (1 + rho) / (1 - rho)) = 0.0071; the bound is 4 of them (p = 6e-5).
    # The kinetic temperature's mean is kT / (1 - (omega h)^2 / 4) = 1.0025 under BAOAB (its
    # momentum bias for a harmonic mode); the same 4 sigma (N_f = 200) around it.
    n_bodies, n = 100, 2
    table = thermostat_table("langevin", gamma="20.0")
    path = ctx.write("cluster.toml", harmonic_cluster_scene(n_bodies, 9, "0.01", "102.0", 50, table, check_every=50))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--out", out, "-q"), "Langevin harmonic cluster")
    columns = diagnostics_columns(out)
    rows = [k for k, t in enumerate(columns["t"]) if t >= 2.0 - 1e-9]
    check(len(rows) == 201, f"{len(rows)} rows from t = 2")
    nu, m, rho = (n_bodies - 1) * n, len(rows), ((1.0 + 5.0) * math.exp(-5.0)) ** 2
    sigma = math.sqrt(2.0 / nu / m * (1.0 + rho) / (1.0 - rho))
    conf = sum(columns["configurational_temperature"][k] for k in rows) / m
    check(abs(conf - 1.0) < 4.0 * sigma, f"mean configurational temperature {conf}, expected 1 within {4 * sigma}")
    sigma_k = math.sqrt(2.0 / (n_bodies * n) / m * (1.0 + rho) / (1.0 - rho))
    kinetic = sum(columns["kinetic_temperature"][k] for k in rows) / m
    expected = 1.0 / (1.0 - (10.0 * 0.01) ** 2 / 4.0)
    check(abs(kinetic - expected) < 4.0 * sigma_k,
          f"mean kinetic temperature {kinetic}, expected {expected} within {4 * sigma_k}")


@case
def thermostat_nose_hoover_schedule_conserved(ctx):
    # Nose-Hoover's extended energy holds N_f kT xi_1 and masses Q ~ kT: a schedule changes it at a
    # fixed state, by a jump the integrator takes out of `conserved`, which then stays constant up
    # to the method's error while kT moves. Ideal gas, N = 100 (N_f = 200), kT 2 -> 0.5 over
    # t in [0, 1], tau = 0.5: a jump left in would be ~ N_f dkT xi_1 ~ 200 x 1.5 x O(1), of the order
    # of K0 = N kT0 = 200 itself; the method's error is that of the Trotter splitting
    # NHC(h/2) step NHC(h/2), O((h / tau)^2) = 4e-4 of K0 (h = 0.01; the NVE step's own error on this
    # gas is below 1e-7 K0). Bound: 1e-3 K0, with the guard at that level too (the run must complete).
    table = thermostat_table("nose-hoover", temperature="[[0.0, 2.0], [1.0, 0.5]]")
    path = ctx.write("quench.toml", ideal_gas_scene(100, 2.0, 12, "0.01", "2.0", 10, table, guard=1e-3))
    out = ctx.work / "out"
    expect_ok(ctx.run("run", path, "--out", out, "-q"), "Nose-Hoover quench with energy_guard = 1e-3")
    s = summary(out)
    k0 = s["energy"]["initial"]
    drift = s["thermostat"]["conserved"]["max_abs_drift"]
    check(drift < 1e-3 * k0, f"conserved drifted by {drift} under the schedule (K0 = {k0})")
    columns = diagnostics_columns(out)
    final = columns["kinetic_temperature"][-1]
    check(final < 1.0, f"no quench: kinetic temperature {final} at the end")
