#!/usr/bin/python3
"""A flat periodic Lennard-Jones scene for sesi and the same system for LAMMPS (issue #26).

    python3 tools/lammps_data.py lattice OUT.toml --dim 2|3 [--per-side 18] [--density 0.7]
        [--perturb 0.1] [--temperature 1] [--seed 1] [--dt 0.005] [--t-end 5] [--output-every 10]
    python3 tools/lammps_data.py convert SCENE.toml OUT_DIR [--steps 0] [--dt DT] [--thermo-every 10]
        [--skin 0.3]
    python3 tools/lammps_data.py scene DATA OUT.toml --dim 2|3 [--epsilon 1] [--sigma 1] [--cutoff 2.5]
        [--dt 0.005] [--t-end 5] [--method sesi2]

`lattice` writes a sesi scene: a square (2-D) or simple cubic (3-D) lattice of per-side^dim
bodies of unit mass at the given number density (spacing density^(-1/dim), sites at the cell
centres, box [0, L) with L = per-side x spacing), each coordinate moved by a uniform deviate of
+-perturb spacings, velocities normal of deviation sqrt(kT / m) with the mean momentum removed,
Lennard-Jones epsilon = sigma = 1, cutoff 2.5, method sesi2. Python's Mersenne Twister with a
fixed seed, numbers written with repr (17 significant digits at most, exact to the bit).

`convert` reads a sesi scene with `[space] kind = "euclidean"`, dim 2 or 3, `box = [...]`, bodies
given by `x` (and `v`, default 0) and one `lennard-jones` term, and writes OUT_DIR/system.data
(LAMMPS data file, atom_style atomic: one atom type per distinct mass, positions and velocities
with 17 significant digits, so LAMMPS reads the same doubles) and OUT_DIR/in.lammps: units lj,
periodic box [0, L_k) (2-D: dimension 2, z in [-0.5, 0.5)), pair_style lj/cut with
`pair_modify shift yes` (sesi's Lennard-Jones is shifted to 0 at the cutoff, forces truncated),
`neighbor SKIN bin` rebuilt whenever a body moved half the skin (`neigh_modify every 1 delay 0
check yes`, so no pair is missed), thermo step / pe / ke of the whole box (`thermo_modify norm
no`) with `%.17g`, and with --steps 0 a dump of `id x y z fx fy fz` (`%.17g`, sorted by id) into
OUT_DIR/forces.dump; with --steps S > 0 `fix nve` (velocity Verlet) for S steps of the scene's
dt (or --dt). Atom ids are the scene's body numbers plus one. Run it as
`lmp -in OUT_DIR/in.lammps -log OUT_DIR/log.lammps -screen none` from any directory (the paths
in the script are absolute).

`scene` is the reverse: a LAMMPS data file (atom_style atomic: `Masses`, `Atoms` with
`id type x y z`, optional `Velocities`; an orthogonal box, no tilt) to a sesi scene with
`box = [hi - lo, ...]` and the atoms moved by -lo (so the domain is [0, L_k)), in id order, and one
lennard-jones term with the given parameters (pair coefficients are in the input script, not the
data file). A 2-D system (--dim 2) drops z.
"""
import argparse
import math
import os
import random
import sys
import tomllib


def lattice_scene(dim, per_side, density, perturb, temperature, seed, dt, t_end, output_every):
    """The text of a sesi scene (see the module's doc)."""
    rng = random.Random(seed)
    a = density ** (-1.0 / dim)
    box = per_side * a
    positions, velocities = [], []
    for index in range(per_side ** dim):
        site = [(index // per_side ** k) % per_side for k in range(dim)]
        positions.append([(s + 0.5 + rng.uniform(-perturb, perturb)) * a for s in site])
    sd = math.sqrt(temperature)
    for _ in positions:
        velocities.append([rng.gauss(0.0, sd) for _ in range(dim)])
    n = len(positions)
    mean = [sum(v[k] for v in velocities) / n for k in range(dim)]
    velocities = [[v[k] - mean[k] for k in range(dim)] for v in velocities]
    vec = lambda xs: "[" + ", ".join(repr(float(x)) for x in xs) + "]"  # noqa: E731
    lines = [f"# {n} Lennard-Jones bodies in a periodic {dim}-D box at density {density} "
             f"(tools/lammps_data.py lattice, seed {seed})",
             f'name = "lj-box-{dim}d-{n}"', "", "[space]", 'kind = "euclidean"', f"dim = {dim}",
             f"box = {vec([box] * dim)}", ""]
    for x, v in zip(positions, velocities):
        lines += ["[[bodies]]", "mass = 1.0", f"x = {vec(x)}", f"v = {vec(v)}"]
    lines += ["", "[[potential]]", 'kind = "lennard-jones"', "epsilon = 1.0", "sigma = 1.0", "cutoff = 2.5", "",
              "[integrator]", 'method = "sesi2"', f"dt = {dt!r}", f"t_end = {t_end!r}",
              f"output_every = {output_every}", ""]
    return "\n".join(lines)


class SceneError(Exception):
    pass


def read_scene(path):
    """(dim, box, masses, positions, velocities, lj dict, dt) of a flat periodic LJ scene."""
    with open(path, "rb") as f:
        scene = tomllib.load(f)
    space = scene.get("space", {})
    if space.get("kind") != "euclidean":
        raise SceneError(f"{path}: [space] kind must be \"euclidean\" (LAMMPS' flat box), not {space.get('kind')!r}")
    dim = space.get("dim")
    if dim not in (2, 3):
        raise SceneError(f"{path}: [space] dim must be 2 or 3 for LAMMPS, not {dim!r}")
    box = space.get("box")
    if not isinstance(box, list) or len(box) != dim or not all(
            isinstance(e, (int, float)) and math.isfinite(e) and e > 0 for e in box):
        raise SceneError(f"{path}: [space] box must be {dim} finite edges > 0, not {box!r}")
    box = [float(e) for e in box]
    terms = scene.get("potential", [])
    if len(terms) != 1 or terms[0].get("kind") != "lennard-jones":
        raise SceneError(f"{path}: exactly one [[potential]] of kind \"lennard-jones\" is converted")
    lj = {"epsilon": float(terms[0].get("epsilon", 1.0)), "sigma": float(terms[0].get("sigma", 1.0))}
    lj["cutoff"] = float(terms[0].get("cutoff", 2.5 * lj["sigma"]))
    masses, positions, velocities = [], [], []
    for k, body in enumerate(scene.get("bodies", [])):
        if "x" not in body:
            raise SceneError(f"{path}: body {k + 1}: give its position as x (chart q and p are not converted)")
        x = [float(c) for c in body["x"]]
        v = [float(c) for c in body.get("v", [0.0] * dim)]
        if len(x) != dim or len(v) != dim:
            raise SceneError(f"{path}: body {k + 1}: x and v need {dim} components")
        # LAMMPS keeps atoms in [lo, hi); reduce as sesi does (domain [0, L_k)).
        for i in range(dim):
            x[i] -= box[i] * math.floor(x[i] / box[i])
            if x[i] >= box[i]:  # a tiny negative coordinate rounds to L
                x[i] = 0.0
        masses.append(float(body.get("mass", 1.0)))
        positions.append(x)
        velocities.append(v)
    if not positions:
        raise SceneError(f"{path}: no bodies")
    dt = scene.get("integrator", {}).get("dt")
    return dim, box, masses, positions, velocities, lj, dt


def write_lammps(scene_path, out_dir, steps, dt, thermo_every, skin):
    dim, box, masses, positions, velocities, lj, scene_dt = read_scene(scene_path)
    dt = dt if dt is not None else scene_dt
    if steps > 0 and not (isinstance(dt, (int, float)) and dt > 0):
        raise SceneError(f"{scene_path}: a run needs dt > 0 (the scene's [integrator] dt or --dt)")
    os.makedirs(out_dir, exist_ok=True)
    out_dir = os.path.abspath(out_dir)
    kinds = sorted(set(masses))
    g = lambda x: format(x, ".17g")  # noqa: E731
    data = [f"LAMMPS data file from {os.path.basename(scene_path)} (tools/lammps_data.py)", "",
            f"{len(positions)} atoms", f"{len(kinds)} atom types", "",
            f"0 {g(box[0])} xlo xhi", f"0 {g(box[1])} ylo yhi",
            (f"0 {g(box[2])} zlo zhi" if dim == 3 else "-0.5 0.5 zlo zhi"), "", "Masses", ""]
    data += [f"{t + 1} {g(m)}" for t, m in enumerate(kinds)]
    data += ["", "Atoms # atomic", ""]
    for k, (m, x) in enumerate(zip(masses, positions)):
        z = x + [0.0] * (3 - dim)
        data.append(f"{k + 1} {kinds.index(m) + 1} {g(z[0])} {g(z[1])} {g(z[2])}")
    data += ["", "Velocities", ""]
    for k, v in enumerate(velocities):
        w = v + [0.0] * (3 - dim)
        data.append(f"{k + 1} {g(w[0])} {g(w[1])} {g(w[2])}")
    with open(os.path.join(out_dir, "system.data"), "w") as f:
        f.write("\n".join(data) + "\n")
    script = [f"# {scene_path} for LAMMPS (tools/lammps_data.py convert)", "units lj", f"dimension {dim}",
              "boundary p p p", "atom_style atomic", "atom_modify map array",
              f"read_data {os.path.join(out_dir, 'system.data')}",
              f"pair_style lj/cut {g(lj['cutoff'])}",
              f"pair_coeff * * {g(lj['epsilon'])} {g(lj['sigma'])} {g(lj['cutoff'])}",
              "pair_modify shift yes", f"neighbor {g(skin)} bin", "neigh_modify every 1 delay 0 check yes",
              "compute kinetic all ke", "thermo_style custom step pe c_kinetic",
              "thermo_modify norm no format float %.17g", f"thermo {max(1, thermo_every)}"]
    if steps == 0:
        script += [f"dump forces all custom 1 {os.path.join(out_dir, 'forces.dump')} id x y z fx fy fz",
                   "dump_modify forces format float %.17g sort id", "run 0"]
    else:
        script += ["fix integrate all nve"]
        if dim == 2:
            script += ["fix plane all enforce2d"]
        script += [f"timestep {g(dt)}", f"run {steps}"]
    with open(os.path.join(out_dir, "in.lammps"), "w") as f:
        f.write("\n".join(script) + "\n")


def data_to_scene(data_path, dim, lj, dt, t_end, method):
    """The text of a sesi scene from a LAMMPS data file (see the module's doc)."""
    lo, hi, masses, atoms, velocities, section = [0.0] * 3, [0.0] * 3, {}, {}, {}, None
    with open(data_path) as f:
        next(f, None)  # the title line
        for line in f:
            words = line.split("#")[0].split()
            if not words:
                continue
            if words[0] in ("Masses", "Atoms", "Velocities"):
                section = words[0]
            elif words[0][0].isalpha():
                raise SceneError(f"{data_path}: section {words[0]} is not converted (atom_style atomic only)")
            elif section is None:
                if len(words) == 3 and words[2] == "xy":
                    raise SceneError(f"{data_path}: a triclinic box is not converted")
                for k, axis in enumerate("xyz"):
                    if words[2:4] == [f"{axis}lo", f"{axis}hi"]:
                        lo[k], hi[k] = float(words[0]), float(words[1])
            elif section == "Masses":
                masses[int(words[0])] = float(words[1])
            elif section == "Atoms":
                atoms[int(words[0])] = (int(words[1]), [float(w) for w in words[2:5]])
            else:
                velocities[int(words[0])] = [float(w) for w in words[1:4]]
    box = [hi[k] - lo[k] for k in range(dim)]
    if not atoms or not all(e > 0 for e in box):
        raise SceneError(f"{data_path}: no atoms or no box")
    vec = lambda xs: "[" + ", ".join(repr(float(x)) for x in xs) + "]"  # noqa: E731
    lines = [f"# {len(atoms)} atoms from {os.path.basename(data_path)} (tools/lammps_data.py scene)",
             f'name = "{os.path.splitext(os.path.basename(data_path))[0]}"', "", "[space]", 'kind = "euclidean"',
             f"dim = {dim}", f"box = {vec(box)}", ""]
    for ident in sorted(atoms):
        kind, x = atoms[ident]
        if kind not in masses:
            raise SceneError(f"{data_path}: atom {ident}: type {kind} has no mass")
        v = velocities.get(ident, [0.0, 0.0, 0.0])
        lines += ["[[bodies]]", f"mass = {masses[kind]!r}", f"x = {vec([x[k] - lo[k] for k in range(dim)])}",
                  f"v = {vec(v[:dim])}"]
    lines += ["", "[[potential]]", 'kind = "lennard-jones"', f"epsilon = {lj['epsilon']!r}",
              f"sigma = {lj['sigma']!r}", f"cutoff = {lj['cutoff']!r}", "", "[integrator]", f'method = "{method}"',
              f"dt = {dt!r}", f"t_end = {t_end!r}", ""]
    return "\n".join(lines)


def read_thermo(log_path):
    """[(step, pe, ke)] from a LAMMPS log written by a convert script."""
    rows, reading = [], False
    with open(log_path) as f:
        for line in f:
            words = line.split()
            if words[:3] == ["Step", "PotEng", "c_kinetic"]:
                reading = True
            elif reading and words and words[0] == "Loop":
                reading = False
            elif reading and len(words) == 3:
                rows.append((int(words[0]), float(words[1]), float(words[2])))
    return rows


def read_dump(dump_path):
    """{id: (x, y, z, fx, fy, fz)} of the last frame of a convert script's force dump."""
    atoms, lines = {}, open(dump_path).read().splitlines()
    start = max(k for k, line in enumerate(lines) if line.startswith("ITEM: ATOMS"))
    for line in lines[start + 1:]:
        words = line.split()
        atoms[int(words[0])] = tuple(float(w) for w in words[1:7])
    return atoms


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    la = sub.add_parser("lattice")
    la.add_argument("out")
    la.add_argument("--dim", type=int, choices=(2, 3), required=True)
    la.add_argument("--per-side", type=int, default=None)
    la.add_argument("--density", type=float, default=0.7)
    la.add_argument("--perturb", type=float, default=0.1)
    la.add_argument("--temperature", type=float, default=1.0)
    la.add_argument("--seed", type=int, default=1)
    la.add_argument("--dt", type=float, default=0.005)
    la.add_argument("--t-end", type=float, default=5.0)
    la.add_argument("--output-every", type=int, default=10)
    co = sub.add_parser("convert")
    co.add_argument("scene")
    co.add_argument("out_dir")
    co.add_argument("--steps", type=int, default=0)
    co.add_argument("--dt", type=float, default=None)
    co.add_argument("--thermo-every", type=int, default=10)
    co.add_argument("--skin", type=float, default=0.3)
    sc = sub.add_parser("scene")
    sc.add_argument("data")
    sc.add_argument("out")
    sc.add_argument("--dim", type=int, choices=(2, 3), required=True)
    sc.add_argument("--epsilon", type=float, default=1.0)
    sc.add_argument("--sigma", type=float, default=1.0)
    sc.add_argument("--cutoff", type=float, default=2.5)
    sc.add_argument("--dt", type=float, default=0.005)
    sc.add_argument("--t-end", type=float, default=5.0)
    sc.add_argument("--method", default="sesi2")
    a = ap.parse_args()
    try:
        if a.command == "lattice":
            per_side = a.per_side if a.per_side is not None else (18 if a.dim == 2 else 7)
            if per_side < 1 or not a.density > 0 or not 0 <= a.perturb < 0.5 or not a.temperature >= 0:
                raise SceneError("lattice: --per-side >= 1, --density > 0, --perturb in [0, 0.5), --temperature >= 0")
            text = lattice_scene(a.dim, per_side, a.density, a.perturb, a.temperature, a.seed, a.dt, a.t_end,
                                 a.output_every)
            with open(a.out, "w") as f:
                f.write(text)
        elif a.command == "scene":
            lj = {"epsilon": a.epsilon, "sigma": a.sigma, "cutoff": a.cutoff}
            text = data_to_scene(a.data, a.dim, lj, a.dt, a.t_end, a.method)
            with open(a.out, "w") as f:
                f.write(text)
        else:
            if a.steps < 0 or a.thermo_every < 1 or not a.skin >= 0:
                raise SceneError("convert: --steps >= 0, --thermo-every >= 1, --skin >= 0")
            write_lammps(a.scene, a.out_dir, a.steps, a.dt, a.thermo_every, a.skin)
    except (SceneError, OSError, tomllib.TOMLDecodeError) as e:
        print(f"lammps_data.py: {e}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
