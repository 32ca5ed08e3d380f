# Every method in high dimensions (issue #24): a random three-body scene on S^n and H^n, n = 2..12
# (the program's dynamic dimension above 8), against a fine reference. The chart methods must be
# about as accurate as their geodesic twins (the same table over the embedding, which has no
# chart). Before the program re-charted the initial state, a body that started near a pole took
# its first step in the singular chart: on these scenes' S^9 and H^9 sesi8-kahan-li ended 2.3e-4
# and 0.15 off where geodesic8-kahan-li was 1e-13 and 1e-12 (docs/scheme.md).
# Exec'd in check_program.py's namespace: case, check, expect_ok, summary come from there.

import random as high_dim_random

# Every method, with its order and its geodesic twin (the same table; else one of the same order).
HIGH_DIM_METHODS = {
    "sesi2": (2, "geodesic2"), "sesi4": (4, "geodesic4"), "sesi4-suzuki": (4, "geodesic4"),
    "sesi4-mclachlan": (4, "geodesic4"), "sesi6": (6, "geodesic6"), "sesi6-kahan-li": (6, "geodesic6-kahan-li"),
    "sesi8": (8, "geodesic8"), "sesi8-kahan-li": (8, "geodesic8-kahan-li"),
    "sesi6-processed": (6, "geodesic6-processed"), "sesi8-processed": (8, "geodesic8-processed"),
    "sesi10-processed": (10, "geodesic10-processed"),
}
HIGH_DIM_GEODESIC = sorted({twin for _, twin in HIGH_DIM_METHODS.values()})


def high_dim_scene(kind, n, seed, speed, radius=1.3):
    """Three unit masses at random points with random velocities (Gaussian components, speed
    about `speed` per coordinate), in a harmonic pair well (k = 1, d0 = 0.5); on H^n between 0.5
    and 1.5 radii from the origin (nearer, at the chart's polar origin, a receding body stays in
    the scene's chart, slower at every dimension: docs/scheme.md)."""
    g = high_dim_random.Random(seed)
    text = f'[space]\nkind = "{kind}"\ndim = {n}\nradius = {radius}\n\n'
    for _ in range(3):
        u = [g.gauss(0, 1) for _ in range(n + 1)]
        w = [g.gauss(0, 1) for _ in range(n + 1)]
        if kind == "sphere":
            norm = math.sqrt(sum(c * c for c in u))
            x = [radius * c / norm for c in u]
            along = sum(a * b for a, b in zip(x, w)) / (radius * radius)
            v = [speed * (b - along * a) for a, b in zip(x, w)]
        else:  # x = (R sinh r e, R cosh r), 0.5 <= r <= 1.5; v tangent: <x, v>_L = 0
            spatial = u[:n]
            norm = math.sqrt(sum(c * c for c in spatial))
            r = 0.5 + min(1.0, abs(u[n]))
            x = [radius * math.sinh(r) * c / norm for c in spatial] + [radius * math.cosh(r)]
            w = w[:n]
            last = sum(a * b for a, b in zip(x[:n], w)) / x[n]
            v = [speed * c for c in w + [last]]
        text += "[[bodies]]\nmass = 1.0\nx = [%s]\nv = [%s]\n\n" % (
            ", ".join(repr(c) for c in x), ", ".join(repr(c) for c in v))
    return text + '[[potential]]\nkind = "harmonic-pair"\nk = 1.0\nd0 = 0.5\n'


def high_dim_final(ctx, scene, method, dt, tag):
    out = ctx.work / tag
    expect_ok(ctx.run("run", scene, "--method", method, "--dt", dt, "--t-end", "3", "--output-every", "100000",
                      "--check-every", "100000", "--out", out, "-q"), tag)
    s = summary(out)
    check(s["complete"] is True, f"{tag}: {s['stop_reason']}")
    return [c for b in s["final_state"]["bodies"] for c in b["x"]]


def high_dim_check(ctx, kind, seed, speed):
    worst = {}
    for n in range(2, 13):
        scene = ctx.write(f"{kind}{n}.toml", high_dim_scene(kind, n, seed, speed))
        reference = high_dim_final(ctx, scene, "geodesic8-kahan-li", 0.001, f"{kind}{n}-reference")
        error = {}
        for method in list(HIGH_DIM_METHODS) + HIGH_DIM_GEODESIC:
            final = high_dim_final(ctx, scene, method, 0.01, f"{kind}{n}-{method}")
            error[method] = max(abs(a - b) for a, b in zip(final, reference))
        for method, (order, twin) in HIGH_DIM_METHODS.items():
            # The chart splits the kinetic energy into n levels, the geodesic step does not: its
            # error terms add the commutators of n (n - 1) / 2 pairs of levels. A level that moves
            # with the factor 1/P^2 of the kinetic energy turns by dt v / (R P) in a step; with
            # P >= 1/4 where bodies move (re-charting, docs/charts.md) that is at most 4 times the
            # geodesic step's rate, and a local error term O((rate dt)^(p+1)) at most 4^(p+1)
            # times the twin's. The floor: the round-off of 300 steps of up to 23 stages and of
            # the reference's 3000 of 17, eps each, added up: 2e-11.
            bound = (1 + n * (n - 1) / 2) * 4.0 ** (order + 1) * error[twin] + 2e-11
            ratio = error[method] / bound
            if ratio > worst.get(method, (0, 0))[0]:
                worst[method] = (ratio, n)
            check(error[method] <= bound, f"{kind} n = {n}: {method} {error[method]:.3g} off, its geodesic twin "
                                          f"{twin} {error[twin]:.3g}: more than {bound:.3g}")
    for method, (ratio, n) in worst.items():
        print(f"{kind}: {method}: at most {ratio:.3g} of its bound (n = {n})")


@case
def high_dim_sphere(ctx):
    """S^n, n = 2..12 (R = 1.3, t = 3, dt = 0.01): every chart method within its bound."""
    high_dim_check(ctx, "sphere", seed=82, speed=2.0)


@case
def high_dim_hyperbolic(ctx):
    """H^n, n = 2..12, as high_dim_sphere."""
    high_dim_check(ctx, "hyperbolic", seed=30, speed=1.5)
