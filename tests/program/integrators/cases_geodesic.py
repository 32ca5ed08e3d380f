# The geodesic methods (issue #15 item 3): the embedding splitting of include/sesi/reference/
# embedding.hpp as methods of `sesi run` on S^n and H^n (src/integrators/embedded_integrator.hpp).
# Exec'd in check_program.py's namespace: case, check, expect_ok, expect_input_error, summary, ...
# come from there; resume_extends and expect_same_outputs from run/cases_checkpoint.py (looked up
# when a case runs).
import re

GEODESIC_METHODS = {"geodesic2": 2, "geodesic4": 4, "geodesic6": 6, "geodesic6-kahan-li": 6, "geodesic8": 8,
                    "geodesic8-kahan-li": 8}


def final_xv(out):
    """The final embedding points and velocities of every body, one flat list."""
    return [c for b in summary(out)["final_state"]["bodies"] for c in b["x"] + b["v"]]


def run_final(ctx, scene, method, dt, t_end, tag):
    out = ctx.work / tag
    expect_ok(ctx.run("run", *scene, "--method", method, "--dt", dt, "--t-end", t_end, "--output-every", "100000",
                      "--out", out, "-q"), tag)
    s = summary(out)
    check(s["method"] == method and s["complete"] is True, f"{tag}: {s['method']} {s['stop_reason']}")
    return final_xv(out)


# Step sizes per order: errors at h/2 far above round-off and in the asymptotic range (the
# methods are symmetric: the next term is h^(p+2), so the observed order approaches p at the rate
# h^2). Measured: on the sphere 2.00, 4.01, 6.01, 6.01, 7.92, 8.01 and on H^2 2.00, 3.98, 5.95,
# 5.98, 7.91, 7.99 for the methods in GEODESIC_METHODS' order (docs/scheme.md).
ORDER_STEPS = {
    "sphere": {2: 0.05, 4: 0.1, 6: 0.2, 8: 0.25},
    "hyperbolic": {2: 0.0125, 4: 0.0125, 6: 0.025, 8: 0.05},
}


def geodesic_orders(ctx, scene, kind, t_end):
    reference = run_final(ctx, scene, "sesi8-kahan-li", 0.001, t_end, f"{kind}-reference")
    for method, order in GEODESIC_METHODS.items():
        h = ORDER_STEPS[kind][order]
        coarse = run_final(ctx, scene, method, h, t_end, f"{kind}-{method}-{h}")
        fine = run_final(ctx, scene, method, h / 2, t_end, f"{kind}-{method}-{h / 2}")
        e1, e2 = math.dist(coarse, reference), math.dist(fine, reference)
        check(e2 > 1e-11, f"{kind} {method}: error {e2:.3g} at h = {h / 2} too close to round-off")
        observed = math.log2(e1 / e2)
        print(f"{kind} {method}: h = {h}: errors {e1:.3e}, {e2:.3e}; observed order {observed:.2f}")
        check(order - 0.3 < observed < order + 0.8,
              f"{kind} {method}: observed order {observed:.2f}, nominal {order} (errors {e1:.3g}, {e2:.3g})")


@case
def geodesic_orders_sphere(ctx):
    """On S^2 (the seed's scene, t = 10): each geodesic method at its order, against a fine
    sesi8-kahan-li run (dt = 0.001, error ~1e-14)."""
    geodesic_orders(ctx, [], "sphere", 10)


@case
def geodesic_orders_hyperbolic(ctx):
    """On H^2 (the Kepler example scene: a central term and gravity, t = 2, distances below 3)."""
    geodesic_orders(ctx, [ctx.scene("hyperbolic-kepler-xv.toml")], "hyperbolic", 2)


@case
def geodesic_energy_bounded(ctx):
    """Symplectic: the energy error stays bounded, no drift. The seed's scene with geodesic4 at
    tau = 0.1: the largest error over t <= 800 is that over t <= 100 (both a few 1e-5)."""
    errors = {}
    for t_end in ("100", "800"):
        out = ctx.work / f"energy-{t_end}"
        expect_ok(ctx.run("run", "--method", "geodesic4", "--t-end", t_end, "--output-every", "100",
                          "--out", out, "-q"), f"geodesic4 to {t_end}")
        errors[t_end] = summary(out)["energy"]["max_abs_error"]
    check(0 < errors["100"] < 1e-3, f"energy error {errors['100']:.3g} to t = 100")
    check(errors["800"] <= 1.5 * errors["100"],
          f"energy error grows: {errors['100']:.3g} to t = 100, {errors['800']:.3g} to t = 800")


@case
def geodesic_keeps_the_quadric(ctx):
    """After many steps through the poles of S^2 and on H^2 the final points are on the quadric and
    the velocities tangent to round-off (|<x,x> - s R^2| and |<x,v>| relative to |x|^2, |x| |v|)."""
    for scene, sign in (("sphere-pole-crossing.toml", 1.0), ("hyperbolic-kepler-xv.toml", -1.0)):
        out = ctx.work / scene
        expect_ok(ctx.run("run", ctx.scene(scene), "--method", "geodesic6", "--t-end", "5", "--out", out, "-q"),
                  scene)
        for body in summary(out)["final_state"]["bodies"]:
            x, v = body["x"], body["v"]
            eta = [1.0] * (len(x) - 1) + [sign]
            xx = sum(e * a * a for e, a in zip(eta, x))
            xv = sum(e * a * b for e, a, b in zip(eta, x, v))
            nx, nv = math.sqrt(sum(a * a for a in x)), math.sqrt(sum(a * a for a in v))
            check(abs(xx - sign) <= 1e-14 * nx * nx, f"{scene}: <x,x> = {xx!r}")
            check(abs(xv) <= 1e-14 * nx * nv, f"{scene}: <x,v> = {xv!r}")


@case
def geodesic_help_lists_methods(ctx):
    run = ctx.run("run", "--help")
    check(run.returncode == 0, f"sesi run --help: {run.returncode}")
    for method in GEODESIC_METHODS:
        check(method in run.stdout, f"sesi run --help does not mention {method}")


@case
def geodesic_refused_on_euclidean(ctx):
    """On E^n the sesi methods are already the flat splitting: a geodesic method is refused with one
    line naming the method and the space, from the command line or the scene file, nothing written."""
    out = ctx.work / "out"
    result = ctx.run("run", ctx.scene("euclidean-figure-eight-qp.toml"), "--method", "geodesic4", "--out", out)
    expect_input_error(result, text="method 'geodesic4'")
    check("euclidean space E^2" in result.stderr, f"stderr does not name the space: {result.stderr!r}")
    check(not out.exists(), "an output directory was created")
    expect_no_staging_left(out)
    text = re.sub(r'(?m)^method = ".*"$', 'method = "geodesic8-kahan-li"',
                  ctx.scene("euclidean-figure-eight-xv.toml").read_text())
    check("geodesic8-kahan-li" in text, "the example scene's method line changed")
    path = ctx.write("flat.toml", text)
    result = ctx.run("run", path, "--out", out)
    expect_input_error(result, text="method 'geodesic8-kahan-li'")
    check("euclidean space E^2" in result.stderr and "sesi8-kahan-li" in result.stderr,
          f"stderr does not name the space and the flat method: {result.stderr!r}")
    check(not out.exists(), "an output directory was created")


@case
def geodesic_resume_sphere(ctx):
    """A checkpointed and resumed geodesic run equals an uninterrupted one byte for byte (S^2 through
    the poles, every geodesic method)."""
    for method in GEODESIC_METHODS:
        resume_extends(ctx, [ctx.scene("sphere-pole-crossing.toml"), "--method", method], "2.3", "5", 30)


@case
def geodesic_resume_hyperbolic(ctx):
    resume_extends(ctx, [ctx.scene("hyperbolic-kepler-xv.toml"), "--method", "geodesic4"], "3.33", "8", 25,
                   "--output-every", "7")


@case
def geodesic_resume_paper(ctx):
    # The default scene: exact.csv too, and a stop row the resumed run must cut.
    resume_extends(ctx, ["--method", "geodesic6"], "1.05", "3", 4, "--output-every", "3")


@case
def geodesic_resume_after_signal(ctx):
    out = ctx.work / "out"
    process, err = stop_default_run(ctx, out, [signal.SIGINT], None, "--method", "geodesic4")
    check(process.returncode == 130, f"exit status {process.returncode}, expected 130: {err!r}")
    stopped_at = summary(out)["final_state"]["step"]
    t2 = f"{(stopped_at + 200) * 0.1:.1f}"
    expect_ok(ctx.run("resume", out, "--t-end", t2, "--quiet"), "sesi resume")
    whole = ctx.work / "whole"
    expect_ok(ctx.run("run", "--method", "geodesic4", "--t-end", t2, "--output-every", "97", "--out", whole,
                      "--quiet"), "uninterrupted run")
    expect_same_outputs(out, whole, "geodesic4 resumed after SIGINT")


def checkpoint_with_method(data, method):
    """The checkpoint bytes with its method replaced and its checksum recomputed (FNV-1a, 64 bits):
    a well-formed file whose state is of the other kind."""
    head, body = data.split(b"\n", 1)
    old = body.split(b"\nmethod ", 1)[1].split(b"\n", 1)[0]
    body = body.replace(b"\nmethod " + old + b"\n", b"\nmethod " + f"{len(method)}:{method}".encode() + b"\n", 1)
    h = 0xcbf29ce484222325
    for c in body:
        h = ((h ^ c) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    magic, version = head.split(b" ")[:2]
    return b"%s %s %d %016x\n" % (magic, version, len(body), h) + body


@case
def geodesic_checkpoint_kinds(ctx):
    """A geodesic run's checkpoint is version 2 (x and v in place of q, p and frames) and a chart
    run's still version 1. Neither goes on with the other kind of method: a checkpoint whose
    method was changed is refused with one line."""
    runs = {}
    for method in ("sesi4", "geodesic4"):
        out = ctx.work / method
        expect_ok(ctx.run("run", "--method", method, "--t-end", "1", "--checkpoint-every", "5", "--out", out, "-q"),
                  method)
        runs[method] = out
    geodesic = (runs["geodesic4"] / "checkpoint").read_bytes()
    chart = (runs["sesi4"] / "checkpoint").read_bytes()
    check(geodesic.startswith(b"sesi-checkpoint 2 ") and b"\nx 3 3 " in geodesic and b"\nq " not in geodesic,
          f"geodesic checkpoint: {geodesic[:120]!r}")
    check(chart.startswith(b"sesi-checkpoint 1 ") and b"\nx " not in chart, f"chart checkpoint: {chart[:120]!r}")
    for out, method, text in ((runs["sesi4"], "geodesic4", "holds a chart method's state"),
                              (runs["geodesic4"], "sesi4", "holds a geodesic method's state")):
        path = out / "checkpoint"
        path.write_bytes(checkpoint_with_method(path.read_bytes(), method))
        before = snapshot(out)
        expect_input_error(ctx.run("resume", out), file=str(path), text=text)
        expect_untouched(out, before)


@case
def geodesic_far_out(ctx):
    """Far out on H^n the geodesic methods lose digits like eps e^(2r/R) (docs/scheme.md): the far
    pair of run/cases_far.py at 10 radii still runs (energy error 2.8e-7 measured, 9e-11 at the
    origin), and a body beyond 15.7 radii is refused with one line naming it."""
    errors = {}
    for D in (0.0, 10.0):
        text, _ = far_pair_scene(D)
        path = ctx.write(f"pair-{int(D)}.toml", text.replace('method = "sesi4"', 'method = "geodesic4"'))
        out = ctx.work / f"pair-{int(D)}"
        expect_ok(ctx.run("run", path, "--out", out, "-q"), f"geodesic4 at D = {D}")
        errors[D] = summary(out)["energy"]["max_abs_error"]
    check(errors[0.0] < 1e-9 and errors[10.0] < 1e-5, f"energy errors {errors}")
    text, _ = far_pair_scene(20.0)
    path = ctx.write("pair-20.toml", text.replace('method = "sesi4"', 'method = "geodesic4"'))
    out = ctx.work / "pair-20"
    expect_input_error(ctx.run("run", path, "--out", out), file=path, key="bodies[1]", text="use a sesi method")
    check(not out.exists(), "an output directory was created")
