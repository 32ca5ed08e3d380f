#!/usr/bin/env python3
"""sesi against LAMMPS on the same flat periodic Lennard-Jones boxes (issue #26; tests/lammps/CMakeLists.txt).

    check_lammps.py --lmp LMP --forces LAMMPS_FORCES [--sesi SESI] --source DIR --work DIR --case NAME

Cases:
  forces_2d, forces_3d: a perturbed square (18^2 = 324 bodies) / cubic (7^3 = 343) lattice at density 0.7
    (tools/lammps_data.py lattice, seed 1), converted to a LAMMPS data file and script (`convert`, run 0,
    lj/cut 2.5 with pair_modify shift yes). LAMMPS' potential energy and forces against lammps_forces
    (sesi's System on Quotient<Euclidean<N>, PeriodicBox>, through the Verlet lists and over all pairs by
    minimum image), each within a round-off bound derived below from the pair terms' magnitudes; the lists
    and all pairs equal to the bit.
  nve_2d: the 2-D box for 1000 steps, LAMMPS' fix nve (velocity Verlet) against `sesi run` with sesi2, at
    dt = h and h/2: the same initial energy to round-off, and both traces' deviations from E0 and their
    difference of order h^2 (see nve()). `--case nve_3d` runs the same on the 3-D box; it is not registered:
    there the lattice melts with a large exchange of energy and LAMMPS' rms falls by 5.35 (order 2.42), too
    near the band's edge for a test.
"""
import argparse
import csv
import math
import os
import shutil
import subprocess
import sys

U = 2.0 ** -53  # unit round-off of double
# Roundings in one pair term (value or force component) in either code, counted generously: LAMMPS forms
# rsq (2-3 multiplies and adds), 1/rsq, its cube, lj1 r6inv - lj2, two products and the component (about 12);
# sesi the distance (a square root more), (sigma/d)^2, ^6, 2 s12 - s6, / d and the unit vector (about 14).
# Each rounding is relative u of a quantity bounded by the pair's magnitude sum (below), so a term's error
# is at most 16 u of that sum per code, 32 u between the two.
PAIR_ROUNDINGS = 32


def fail(message):
    print(f"FAIL: {message}")
    sys.exit(1)


def run(cmd, **kw):
    done = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if done.returncode != 0:
        fail(f"{' '.join(map(str, cmd))} exited {done.returncode}:\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}")
    return done.stdout


def tools(source):
    sys.path.insert(0, os.path.join(source, "tools"))
    import lammps_data  # noqa: E402
    return lammps_data


def make_box(a, ld, dim, name, **lattice):
    work = os.path.join(a.work, name)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    scene = os.path.join(work, "scene.toml")
    with open(scene, "w") as f:
        f.write(ld.lattice_scene(dim, lattice.get("per_side", 18 if dim == 2 else 7), 0.7, 0.1, 1.0, 1,
                                 lattice.get("dt", 0.005), lattice.get("t_end", 5.0), lattice.get("output_every", 10)))
    return work, scene


def minimum_image(xi, xj, box):
    d = [xi[k] - xj[k] for k in range(len(box))]
    return [dk - box[k] * round(dk / box[k]) for k, dk in enumerate(d)]


def pair_sums(positions, box, lj):
    """Per body, the (F, G) of each partner within the cutoff, and the round-off bound of the potential
    energy between the two codes (see the comments)."""
    eps, sig, rc = lj["epsilon"], lj["sigma"], lj["cutoff"]
    n, dim = len(positions), len(box)
    # Error of a displacement component, per code: the image shift x_j + n L (|.| < 2 L) rounds by u 2 L
    # (LAMMPS' ghost atoms, sesi's nearest_image), the difference x_i - y by u r_c; both codes: twice.
    delta = 2 * U * (2 * max(box) + rc) * math.sqrt(dim)  # the displacement vector's error norm between them
    shift = 4 * eps * ((sig / rc) ** 12 - (sig / rc) ** 6)
    rows = [[] for _ in range(n)]
    pairs_e = []  # per pair: (sum of |value terms|, |dV/dr| bound)
    for i in range(n):
        for j in range(i + 1, n):
            d = minimum_image(positions[i], positions[j], box)
            r = math.sqrt(sum(c * c for c in d))
            if r >= rc:
                continue
            s6 = (sig / r) ** 6
            F = 24 * eps * (2 * s6 * s6 + s6) / r  # the force's magnitude sum, >= |f| and every partial term
            G = 24 * eps * (26 * s6 * s6 + 7 * s6) / r ** 2 + F / r  # >= |d f_vec / d r_vec| (radial + turning)
            rows[i].append((F, G))
            rows[j].append((F, G))
            pairs_e.append((4 * eps * (s6 * s6 + s6) + abs(shift), F))
    m = len(pairs_e)
    # Energy: each pair's value within PAIR_ROUNDINGS u of its magnitude sum and |dV/dr| delta from the
    # displacement; the sums: LAMMPS one running sum over the m pairs ((m - 1) u), sesi per-row partial sums
    # then a sum over the n rows ((n_max + n) u), each relative to the sum of |terms|.
    n_max = max(len(r) for r in rows)
    mag = sum(e for e, _ in pairs_e)
    e_bound = PAIR_ROUNDINGS * U * mag + sum(F for _, F in pairs_e) * delta + (m + n_max + n) * U * mag
    return {"rows": rows, "delta": delta, "pairs": m, "n_max": n_max, "energy_bound": e_bound}


def forces(a, dim):
    ld = tools(a.source)
    work, scene = make_box(a, ld, dim, f"forces_{dim}d")
    lmp_dir = os.path.join(work, "lammps")
    ld.write_lammps(scene, lmp_dir, 0, None, 1, 0.3)
    run([a.lmp, "-in", os.path.join(lmp_dir, "in.lammps"), "-log", os.path.join(lmp_dir, "log.lammps"),
         "-screen", "none", "-nocite"], cwd=lmp_dir)
    thermo = ld.read_thermo(os.path.join(lmp_dir, "log.lammps"))
    dump = ld.read_dump(os.path.join(lmp_dir, "forces.dump"))
    _, box, _, positions, _, lj, _ = ld.read_scene(scene)
    # The converter both ways: the scene read back from the data file holds the same doubles.
    back = os.path.join(work, "back.toml")
    with open(back, "w") as f:
        f.write(ld.data_to_scene(os.path.join(lmp_dir, "system.data"), dim, lj, 0.005, 5.0, "sesi2"))
    if ld.read_scene(back)[:6] != ld.read_scene(scene)[:6]:
        fail("tools/lammps_data.py scene does not give back the scene that convert wrote")
    out = run([a.forces, os.path.join(lmp_dir, "system.data"), str(dim), repr(lj["epsilon"]), repr(lj["sigma"]),
               repr(lj["cutoff"])])
    sesi_pe, sesi_f, sesi_g = None, {}, {}
    for line in out.splitlines():
        w = line.split()
        if w[0] == "pe":
            sesi_pe = (float(w[1]), float(w[2]))
        elif w[0] in "fg":
            (sesi_f if w[0] == "f" else sesi_g)[int(w[1])] = [float(v) for v in w[2:]]
    n = len(positions)
    if len(thermo) != 1 or len(dump) != n or len(sesi_f) != n or len(sesi_g) != n or sesi_pe is None:
        fail(f"incomplete outputs: {len(thermo)} thermo rows, {len(dump)} dumped atoms, {len(sesi_f)} sesi forces")
    # Both read the same doubles (LAMMPS keeps atoms inside [0, L) as they are).
    for k, x in enumerate(positions):
        if list(dump[k + 1][:dim]) != x:
            fail(f"LAMMPS moved atom {k + 1}: {dump[k + 1][:dim]} against {x}")
    # The Verlet lists against all pairs: the same sums in the same order (api.md), so the same bits.
    if sesi_pe[0] != sesi_pe[1] or sesi_f != sesi_g:
        fail("sesi's Verlet lists and its all-pairs minimum image differ")

    sums = pair_sums(positions, box, lj)
    rows, delta, m, n_max, e_bound = sums["rows"], sums["delta"], sums["pairs"], sums["n_max"], sums["energy_bound"]
    lmp_pe = thermo[0][1]
    e_diff = abs(lmp_pe - sesi_pe[0])
    print(f"{dim}-D box: {n} bodies, {m} pairs within the cutoff, at most {n_max} per body; pe LAMMPS {lmp_pe!r} "
          f"sesi {sesi_pe[0]!r}: |difference| {e_diff:.3g}, bound {e_bound:.3g}")
    if not e_diff <= e_bound:
        fail(f"potential energy differs by {e_diff:.3g} > {e_bound:.3g}")
    # Forces, per body and component: each pair term within PAIR_ROUNDINGS u F + G delta; the body's sum of
    # its k terms (k - 1) u sum F in each code (LAMMPS' half list adds them in another order than sesi's row).
    worst, worst_ratio = 0.0, 0.0
    for i in range(n):
        k = len(rows[i])
        bound = sum(PAIR_ROUNDINGS * U * F + G * delta for F, G in rows[i]) + 2 * max(k - 1, 0) * U * sum(
            F for F, _ in rows[i])
        for c in range(dim):
            diff = abs(dump[i + 1][3 + c] - sesi_f[i + 1][c])
            worst = max(worst, diff)
            worst_ratio = max(worst_ratio, diff / bound if bound > 0 else (math.inf if diff > 0 else 0))
            if not diff <= bound:
                fail(f"body {i + 1} force component {c}: LAMMPS {dump[i + 1][3 + c]!r} sesi {sesi_f[i + 1][c]!r}, "
                     f"|difference| {diff:.3g} > bound {bound:.3g}")
    print(f"forces: largest |difference| {worst:.3g}, largest difference / bound {worst_ratio:.3g}")
    # Not vacuous: a partner missed or taken at the wrong image moves a force by at least the LJ force at the
    # cutoff, 0.039 epsilon/sigma, and the energy by the pair's value, against bounds near 1e-11 and 1e-9.
    print("PASS")


def read_diagnostics(path):
    with open(path) as f:
        rows = [r for r in csv.DictReader(line for line in f if not line.startswith("#"))]
    return [(float(r["t"]), float(r["energy"])) for r in rows]


def energy_traces(a, ld, work, scene, steps, dt, every):
    """The total energies of LAMMPS (fix nve) and of `sesi run` (sesi2), every `every` steps from 0."""
    lmp_dir = os.path.join(work, f"lammps-{steps}")
    ld.write_lammps(scene, lmp_dir, steps, dt, every, 0.3)
    run([a.lmp, "-in", os.path.join(lmp_dir, "in.lammps"), "-log", os.path.join(lmp_dir, "log.lammps"),
         "-screen", "none", "-nocite"], cwd=lmp_dir)
    lmp = [pe + ke for _, pe, ke in ld.read_thermo(os.path.join(lmp_dir, "log.lammps"))]
    out = os.path.join(work, f"sesi-{steps}")
    run([a.sesi, "run", scene, "--out", out, "--dt", repr(dt), "--t-end", repr(steps * dt), "--output-every",
         str(every), "--method", "sesi2", "--quiet"])
    ses = [e for _, e in read_diagnostics(os.path.join(out, "diagnostics.csv"))]
    if len(lmp) != steps // every + 1 or len(ses) != len(lmp):
        fail(f"{len(lmp)} LAMMPS rows and {len(ses)} sesi rows, expected {steps // every + 1}")
    return lmp, ses


def nve(a, dim):
    """LAMMPS' velocity Verlet against sesi2 over 1000 steps of h = 0.002 (T = 2) and 2000 of h/2, the
    energies compared at the same times (every 0.02). Both methods are symmetric and second order, so each
    trace's deviation e(t) = E(t) - E0 is h^2 c(t) + O(h^4) (the modified Hamiltonian, Hairer, Lubich &
    Wanner, GNI IX.8), and so is the difference of the two traces (the program's sesi2 on E^n is
    drift-kick-drift, Verlet's twin, not the same map). Asserted: the root mean square of each trace's
    deviation and of their difference falls by 2^p with p within 1/2 of 2 when the step halves (ratio in
    (2^1.5, 2^2.5)): the bounds halfway (in log) between order 2 and orders 1 and 3, so the test tells order
    2 from its neighbours, the only claim a comparison of two different second-order maps supports. The
    step is kept where the h^2 term dominates: at h <= 0.0005 the force's jump at the cutoff (truncated LJ,
    in both codes) leaves an error that no longer falls as h^2, and beyond T ~ 2 the chaos of the liquid
    separates the runs at h and h/2. The initial energies agree to the round-off bound of forces()."""
    ld = tools(a.source)
    h, steps = 0.002, 1000
    work, scene = make_box(a, ld, dim, f"nve_{dim}d", dt=h, t_end=steps * h, output_every=10)
    traces = []
    for k in range(2):
        lmp, ses = energy_traces(a, ld, work, scene, steps * 2 ** k, h / 2 ** k, 10 * 2 ** k)
        traces.append(([e - lmp[0] for e in lmp], [e - ses[0] for e in ses], [x - y for x, y in zip(lmp, ses)]))
        if k == 0:
            _, box, _, positions, velocities, lj, _ = ld.read_scene(scene)
            e_bound = pair_sums(positions, box, lj)["energy_bound"]
            kinetic = sum(0.5 * sum(c * c for c in v) for v in velocities)
            # 1/2 m v^2 within 4 u per body, summed in different orders: (n + 4) u sum of them, per code.
            e_bound += 2 * (len(velocities) + 4) * U * kinetic
            print(f"E0: LAMMPS {lmp[0]!r} sesi {ses[0]!r}, |difference| {abs(lmp[0] - ses[0]):.3g}, bound {e_bound:.3g}")
            if not abs(lmp[0] - ses[0]) <= e_bound:
                fail(f"initial energies differ by {abs(lmp[0] - ses[0]):.3g} > {e_bound:.3g}")
    rms = lambda v: math.sqrt(sum(x * x for x in v) / len(v))  # noqa: E731
    for which, name in enumerate(("LAMMPS E - E0", "sesi E - E0", "E_LAMMPS - E_sesi")):
        coarse, fine = rms(traces[0][which]), rms(traces[1][which])
        ratio = coarse / fine if fine > 0 else math.inf
        print(f"{name}: rms {coarse:.4g} at h = {h}, {fine:.4g} at h/2: ratio {ratio:.3f} (order {math.log2(ratio):.2f})")
        if not 2 ** 1.5 < ratio < 2 ** 2.5:
            fail(f"{name}: rms fell by {ratio:.3g} when the step halved, not by 2^(2 +- 1/2)")
    print("PASS")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lmp", required=True)
    ap.add_argument("--forces", required=True)
    ap.add_argument("--sesi")
    ap.add_argument("--source", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--case", required=True)
    a = ap.parse_args()
    if a.case == "forces_2d":
        forces(a, 2)
    elif a.case == "forces_3d":
        forces(a, 3)
    elif a.case in ("nve_2d", "nve_3d"):
        if not a.sesi:
            fail(f"{a.case} needs --sesi")
        nve(a, int(a.case[4]))
    else:
        fail(f"unknown case {a.case}")


if __name__ == "__main__":
    main()
