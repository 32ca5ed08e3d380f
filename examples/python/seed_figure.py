#!/usr/bin/python3
"""The seed paper's Fig. 1 from Python (issue #13): three bodies on S^2 (the seed's scene,
../shared/paper-scene.md) with SESI 2 and SESI 4 at tau = 0.1, against the exact solution: the
XY projection of body 1, the energy error and the angular-momentum error against t.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/seed_figure.py [--t-end 800] [--out seed-figure.png]
"""
import argparse
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import sesi  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--t-end", type=float, default=800.0, help="length of the runs (the seed's: 800)")
    parser.add_argument("--out", default="seed-figure.png", help="the figure (PNG)")
    args = parser.parse_args()

    methods = [("sesi2", "SESI 2"), ("sesi4", "SESI 4")]
    fig, axes = plt.subplots(3, len(methods), figsize=(5 * len(methods), 11), squeeze=False)
    for col, (method, title) in enumerate(methods):
        sim = sesi.Simulation.paper()  # the seed's scene: tau = 0.1
        sim.method = method
        start = time.perf_counter()
        out = sim.run(t_end=args.t_end, output_every=1)
        seconds = time.perf_counter() - start
        t = out["t"]
        exact = sesi.paper_exact(t)
        error = np.max(np.linalg.norm(out["x"] - exact, axis=2))

        ax = axes[0][col]
        ax.plot(exact[:, 0, 0], exact[:, 0, 1], "k-", lw=2.5, alpha=0.35, label="exact")
        ax.plot(out["x"][:, 0, 0], out["x"][:, 0, 1], "-", lw=0.4, label=method)
        ax.set_aspect("equal")
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        ax.set_title(f"{title}, tau = {sim.dt}: {seconds * 1e3:.3g} ms\nlargest distance from exact {error:.2g}",
                     fontsize=10)
        ax.legend(fontsize=7, loc="upper right")

        ax = axes[1][col]
        ax.plot(t, out["energy"] - out["energy"][0], lw=0.6)
        ax.set_xlabel("t")
        ax.set_ylabel("E(t) - E(0)")

        # M12 = L_z, M13 = -L_y, M23 = L_x (sesi.Simulation.momentum_names).
        names = sim.momentum_names
        m = out["momentum"] - out["momentum"][0]
        ax = axes[2][col]
        ax.plot(t, m[:, names.index("M2_3")], lw=0.6, label="L_x")
        ax.plot(t, -m[:, names.index("M1_3")], lw=0.6, label="L_y")
        ax.plot(t, m[:, names.index("M1_2")], lw=0.6, label="L_z")
        ax.set_xlabel("t")
        ax.set_ylabel("L(t) - L(0)")
        ax.legend(fontsize=7)
    fig.suptitle(f"The seed's Fig. 1 from Python: three bodies on S^2, T = {args.t_end:g}")
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
