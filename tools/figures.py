#!/usr/bin/python3
"""The seed paper's two figures from `sesi bench --figure ...` data (issue #4).

    /usr/bin/python3 tools/figures.py seed-fig1 DIR OUT.png     # DIR/seed_fig1.csv
    /usr/bin/python3 tools/figures.py convergence DIR OUT.png   # DIR/convergence.csv

seed-fig1: the seed's Fig. 1 panel (its columns: RK45 = dopri5, implicit midpoint, SESI 2,
SESI 4 at tau = 0.1 to T = 800): XY projection of body 1 over the exact curve, energy error
against t, and the angular-momentum (x, y, z) error against t, with each run's wall time.
convergence: the Supplementary convergence figure, |x_dt(10) - x_dt/2(10)| against dt for
every composition, with slope lines dt^p through each method's first point.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows_of(path):
    with open(path) as f:
        return list(csv.DictReader(l for l in f if not l.startswith("#")))


def seed_fig1(directory, out):
    rows = rows_of(f"{directory}/seed_fig1.csv")
    times = {r["method"]: r for r in rows_of(f"{directory}/seed_fig1_times.csv")}
    series = {}
    for r in rows:
        series.setdefault(r["method"], []).append(r)
    exact = series["exact"]
    methods = [("dopri5", "RK45 (dopri5, rtol 1e-3)"), ("implicit-midpoint", "implicit midpoint"),
               ("sesi2", "SESI 2"), ("sesi4", "SESI 4")]
    fig, axes = plt.subplots(3, 4, figsize=(17, 11))
    for col, (m, title) in enumerate(methods):
        s = series[m]
        t = [float(r["t"]) for r in s]
        ax = axes[0][col]
        ax.plot([float(r["x"]) for r in exact], [float(r["y"]) for r in exact], "k-", lw=2.5,
                alpha=0.35, label="exact")
        ax.plot([float(r["x"]) for r in s], [float(r["y"]) for r in s], "-", lw=0.4, label=m)
        ax.set_aspect("equal")
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        w = times.get(m)
        extra = f"\n{float(w['wall_seconds']) * 1e3:.3g} ms, {w['force_evals']} force evals" if w else ""
        ax.set_title(title + extra, fontsize=10)
        ax.legend(fontsize=7, loc="upper right")
        ax = axes[1][col]
        ax.plot(t, [float(r["energy_error"]) for r in s], lw=0.6)
        ax.set_xlabel("t")
        ax.set_ylabel("E(t) - E(0)")
        ax = axes[2][col]
        # M12 = L_z, M13 = -L_y, M23 = L_x (sesi/diagnostics.hpp).
        ax.plot(t, [float(r["dM23"]) for r in s], lw=0.6, label="L_x")
        ax.plot(t, [-float(r["dM13"]) for r in s], lw=0.6, label="L_y")
        ax.plot(t, [float(r["dM12"]) for r in s], lw=0.6, label="L_z")
        ax.set_xlabel("t")
        ax.set_ylabel("L(t) - L(0)")
        ax.legend(fontsize=7)
    fig.suptitle("The seed's Fig. 1 reproduced: three bodies on S^2, tau = 0.1, T = 800 "
                 "(sesi bench --figure seed-fig1; wall time = min of repeats, no observer)")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"wrote {out}")


def convergence(directory, out):
    rows = rows_of(f"{directory}/convergence.csv")
    methods = []
    for r in rows:
        if r["method"] not in methods:
            methods.append(r["method"])
    fig, ax = plt.subplots(figsize=(9, 7))
    for i, m in enumerate(methods):
        s = [r for r in rows if r["method"] == m]
        dt = [float(r["dt"]) for r in s]
        d = [float(r["difference"]) for r in s]
        order = int(s[0]["order"])
        line, = ax.loglog(dt, d, "o-" if order <= 4 else "D-", ms=4, label=f"{m} (order {order})")
        ref = [d[0] * (x / dt[0]) ** order for x in dt]
        ax.loglog(dt, ref, ":", color=line.get_color(), lw=1)
    ax.set_xlabel("time step dt")
    ax.set_ylabel("|x_dt(10) - x_dt/2(10)|,  x = (theta, phi, p_theta, p_phi) of all bodies")
    ax.set_title("Convergence at t = 10 on the seed's scene (dotted: slope dt^order)\n"
                 "sesi bench --figure convergence")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[1] not in ("seed-fig1", "convergence"):
        print(__doc__)
        sys.exit(2)
    (seed_fig1 if sys.argv[1] == "seed-fig1" else convergence)(sys.argv[2], sys.argv[3])
