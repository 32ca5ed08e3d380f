# Checkpoints and `sesi resume` on a topology (issue #26; docs/scene-format.md, "Checkpoints and
# resume"): format version 4 holds the space's box or genus and every body's image record (image
# counts, words), so that a resumed run equals an uninterrupted one byte for byte, its image
# columns included. Exec'd inside check_program.py: resume_extends, expect_same_outputs,
# rewrite_checkpoint (run/cases_checkpoint.py), thermostat_table (run/cases_thermostat.py) and the
# topology scenes (outputs/cases_topology.py) are in scope.


def topology_checkpoint_version(out):
    return int((pathlib.Path(out) / "checkpoint").read_bytes().split(b" ", 2)[1])


def topology_resume(ctx, name, text, t1, t2, every, *extra):
    path = ctx.write(name, text)
    resume_extends(ctx, [path], t1, t2, every, *extra)
    first = ctx.work / f"first-{t1}"
    check(topology_checkpoint_version(first) == 4, f"{name}: the checkpoint is not format version 4")
    return first


@case
def resume_topology_box(ctx):
    # 16 Lennard-Jones bodies crossing the sides of an 8 x 7 box: stopped at t = 3.1 (a partial
    # output row, cut on resume), resumed to 6.
    edges = [8.0, 7.0]
    first = topology_resume(ctx, "box.toml", topology_box_scene(edges, topology_box_lattice(edges), output_every=40),
                            "3.1", "6", 70)
    _, rows = topology_csv(first)
    check(any(int(c) != 0 for row in rows for b in range(16) for c in row[1 + 8 * b + 6:1 + 8 * b + 8]),
          "no body crossed a side before the end: the image counts were not put to the test")


@case
def resume_topology_box_3d_langevin(ctx):
    # A thermostatted run on a 3-D box: version 4 holds the thermostat's state too.
    import random
    rng = random.Random(9)
    edges = [6.0, 5.5, 5.0]
    bodies = [([(i + 0.5) * 2.0, (j + 0.5) * 1.8, (k + 0.5) * 1.6], [rng.gauss(0, 1) for _ in range(3)])
              for i in range(3) for j in range(3) for k in range(3)]
    text = topology_box_scene(edges, bodies, dt=0.005, t_end=4.0, output_every=30,
                              thermostat=thermostat_table("langevin", temperature="1.5", seed=4))
    topology_resume(ctx, "box3.toml", text, "1.37", "3", 40)


@case
def resume_topology_surface(ctx):
    # Nine Lennard-Jones bodies on the Bolza surface (genus 2, R = 3) crossing its sides.
    radius = 3.0
    text = topology_surface_scene(radius, topology_surface_ring(radius, speed=1.5), lj_cutoff=2.5, t_end=20.0)
    first = topology_resume(ctx, "surface.toml", text, "7.13", "16", 100)
    _, rows = topology_csv(first)
    check(any(row[1 + 11 * b + 10] != "e" for row in rows for b in range(9)),
          "no body crossed a side: the words were not put to the test")


@case
def resume_topology_surface_thermostat(ctx):
    # Genus 3 with a Nose-Hoover chain (version 4 with the thermostat's state).
    radius = 2.5
    text = topology_surface_scene(radius, topology_surface_ring(radius, count=10, speed=1.2, seed=8), genus=3,
                                  lj_cutoff=2.0, t_end=10.0, output_every=20,
                                  thermostat=thermostat_table("nose-hoover", temperature="1.0", tau="0.5"))
    topology_resume(ctx, "surface3.toml", text, "4.05", "9", 60)


@case
def resume_topology_h5md(ctx):
    probe = ctx.run("run", "--t-end", "0", "--trajectory-format", "h5md", "--out", ctx.work / "probe", "-q")
    if probe.returncode != 0:
        raise Skip("sesi is built without HDF5")
    edges = [8.0, 7.0]
    topology_resume(ctx, "box.toml", topology_box_scene(edges, topology_box_lattice(edges), t_end=6.0), "2.05", "5",
                    60, "--trajectory-format", "h5md")
    radius = 3.0
    topology_resume(ctx, "surface.toml", topology_surface_scene(radius, topology_surface_ring(radius, speed=1.5),
                                                                t_end=12.0),
                    "5.01", "10", 100, "--trajectory-format", "h5md")


@case
def resume_topology_refuses_bad_image_record(ctx):
    # A hand-edited version 4 checkpoint (checksum recomputed) with a letter that is no side of the
    # polygon, or image counts of the wrong size: refused with one line, nothing changed.
    radius = 3.0
    path = ctx.write("surface.toml", topology_surface_scene(radius, topology_surface_ring(radius), t_end=3.0))
    for what, edit, text in [
            # (the first word becomes the one letter 8: the sides are 0 .. 7)
            ("letter", lambda body: body.replace(b"\nwords 9 ", b"\nwords 9 1 8 ", 1), "out of range"),
            ("words", lambda body: body.replace(b"\nwords 9 ", b"\nwords 8 ", 1), "the words do not match the bodies")]:
        out = ctx.work / f"out-{what}"
        expect_ok(ctx.run("run", path, "--checkpoint-every", "50", "--out", out, "-q"), "run")
        rewrite_checkpoint(out / "checkpoint", edit=edit)
        before = snapshot(out)
        expect_input_error(ctx.run("resume", out, "--t-end", "4"), file=str(out / "checkpoint"), text=text)
        expect_untouched(out, before)
