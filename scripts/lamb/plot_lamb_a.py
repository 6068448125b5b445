#!/usr/bin/env python3
"""Analytic seismograms of seed 000 §3 case A (explosive line source 1 m deep, 300 Hz first
derivative of a Gaussian, receivers at the surface at 10, 14, ..., 38 m) -> docs/img/lamb_a_analytic.png.

Solid: Cagniard-de Hoop; dashed: independent wavenumber integration (they overlap); dotted:
their difference x 1e4.  Vertical ticks: P (sqrt(x^2+h^2)/Vp), S (sqrt(x^2+h^2)/Vs) and Rayleigh
(x/c_R) travel times plus the wavelet delay t0.
Usage: python3 scripts/lamb/plot_lamb_a.py [--out PATH] [--f0 300] [--vp 2611]
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lamb2d  # noqa: E402


def main():
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(root, "docs", "img", "lamb_a_analytic.png"))
    ap.add_argument("--vp", type=float, default=2611.0)
    ap.add_argument("--vs", type=float, default=1846.0)
    ap.add_argument("--rho", type=float, default=2200.0)
    ap.add_argument("--f0", type=float, default=300.0)
    ap.add_argument("--depth", type=float, default=1.0)
    ap.add_argument("--t-end", type=float, default=0.03)
    ap.add_argument("--dt", type=float, default=1e-5)
    args = ap.parse_args()

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    med = lamb2d.Medium(args.vp, args.vs, args.rho)
    stf = lamb2d.SourceTimeFunction("gaussian_derivative", args.f0)
    offsets = np.arange(10.0, 38.0 + 1e-9, 4.0)
    t = np.arange(int(round(args.t_end / args.dt)) + 1) * args.dt
    ux, uy = lamb2d.seismograms_cagniard(med, "explosion", args.depth, offsets, t, stf)
    wx, wy = lamb2d.seismograms_wavenumber(med, "explosion", args.depth, offsets, t, stf)
    cr = lamb2d.rayleigh_speed(args.vp, args.vs)

    fig, axes = plt.subplots(1, 2, figsize=(11, 7), sharey=True)
    for ax, u, w, name in ((axes[0], ux, wx, "horizontal $u_x$"), (axes[1], uy, wy, "vertical $u_y$ (up)")):
        scale = 0.45 * 4.0 / np.max(np.abs(u))
        for i, x in enumerate(offsets):
            ax.plot(t * 1e3, x + scale * u[i], "k-", lw=1.0, label="Cagniard-de Hoop" if i == 0 else None)
            ax.plot(t * 1e3, x + scale * w[i], "r--", lw=0.8, label="wavenumber integration" if i == 0 else None)
            ax.plot(t * 1e3, x + 1e4 * scale * (w[i] - u[i]), "b:", lw=0.8,
                    label="difference x 1e4" if i == 0 else None)
            r = np.hypot(x, args.depth)
            for tt, col in ((r / args.vp, "g"), (r / args.vs, "m"), (x / cr, "orange")):
                ax.plot([1e3 * (tt + stf.t0)] * 2, [x - 1.2, x + 1.2], color=col, lw=1.2)
        ax.set_title(f"{name}, peak {np.max(np.abs(u)):.3g} m")
        ax.set_xlabel("t [ms]")
        ax.set_xlim(0, 1e3 * t[-1])
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("offset x [m]  (traces scaled, common scale per panel)")
    axes[0].legend(loc="lower right", fontsize=8)
    fig.suptitle(f"Lamb case A: explosive line source M0 = 1 N·m/m at h = {args.depth:g} m, "
                 f"{args.f0:g} Hz Gaussian derivative (t0 = {1e3 * stf.t0:.1f} ms)\n"
                 f"Vp {args.vp:g}, Vs {args.vs:g} m/s, rho {args.rho:g}, c_R {cr:.1f} m/s; "
                 "ticks: P (green), S (magenta), Rayleigh (orange) + t0")
    fig.tight_layout()
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    fig.savefig(args.out, dpi=110)
    worst = max(lamb2d.misfit(w, u) for w, u in zip(np.vstack([wx, wy]), np.vstack([ux, uy])))
    print(f"wrote {args.out}; max misfit wavenumber vs Cagniard {worst:.2e}")


if __name__ == "__main__":
    main()
