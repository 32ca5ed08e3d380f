# The close-encounter check of a many-body run (from 256 bodies, pair sums by rows) reads the
# Verlet lists the forces keep instead of building a neighbour index of its own (issue #27: one
# neighbour structure per step; Integrator::listed_close_pairs). Exec'd inside check_program.py:
# its helpers and cases_threads.py's scene makers are in scope.


def closest_pair(row, header, n, radius):
    """The closest pair (geodesic distance on S^2, 1-based bodies) of one trajectory row."""
    col = {name: k for k, name in enumerate(header)}
    xs = [[row[col[f"b{b}_x{i}"]] for i in (1, 2, 3)] for b in range(1, n + 1)]
    best = (math.inf, 0, 0)
    for i in range(n):
        xi = xs[i]
        for j in range(i + 1, n):
            c = math.dist(xi, xs[j])
            if c < best[0]:
                best = (c, i + 1, j + 1)
    chord, i, j = best
    return 2.0 * radius * math.asin(min(1.0, chord / (2.0 * radius))), i, j


@case
def encounter_check_reads_the_verlet_lists(ctx):
    # 300 bodies on S^2 at density 1/2 (nearest neighbours ~1.4 apart), speeds ~2: some pair comes
    # within 1.0 after a few dozen steps. A floor of 1.0 on Lennard-Jones (min_distance) stops the
    # run at the first check below it, which must be the first checked row where the brute-force
    # closest pair of the same run without a floor is below 1.0, naming that pair.
    n, floor, every = 300, 1.0, 5
    text = threads_sphere_scene(n, 2.0, 43, method="sesi2", t_end="0.5", dt="0.005", output_every=every)
    radius = math.sqrt(2.0 * n / (4.0 * math.pi))
    free = ctx.write("free.toml", text.replace("cutoff = 2.5", "cutoff = 2.5\nmin_distance = 0"))
    floored = ctx.write("floored.toml", text.replace("cutoff = 2.5", f"cutoff = 2.5\nmin_distance = {floor}"))
    out_free, out_floored = ctx.work / "free", ctx.work / "floored"
    result = ctx.run("run", free, "--out", out_free, "--check-every", str(every))
    check(result.returncode == 0, f"free run: {result.stderr!r}")
    header, rows = read_csv(out_free / "trajectory.csv")
    first = None
    for k, row in enumerate(rows):
        d, i, j = closest_pair(row, header, n, radius)
        if d < floor:
            first = (k * every, i, j, d)
            break
    check(first is not None and first[0] > 0, f"no pair came within {floor}: the scene needs faster bodies")
    step, i, j, d = first
    s = expect_run_failure(ctx, ctx.run("run", floored, "--out", out_floored, "--check-every", str(every)),
                           out_floored, "close encounter", f"bodies {i} and {j}", "lennard-jones")
    check(s["failure"]["step"] == step, f"stopped at step {s['failure']['step']}, the pair came within {floor} "
          f"at step {step} ({d:.6f})")
