#!/usr/bin/python3
"""Two properties of the exact projection's pair forces on a perfect lattice (docs/validation.md, ## Fluid).

The projection moves fluid particle k by F_k = -(d/C) sum_j (p_k + p_j) w'(r_kj) e_kj (N^T p with N_ik = dn_i/dx_k),
the force of the potential V = sum_i p_i n_i at fixed pressures.

shear: the smallest stiffness of V, per unit of p, over the lattice's Bloch waves u e^{i k.x} that keep every
  n_i to first order (the constraint cannot see them), for the MPS weight and Wendland's C2 kernel at a few
  radii, on the square lattice (2D). Negative: columns of particles sliding past each other lower V, so a
  lattice under pressure is unstable in shear and the particles leave it at a rate that grows with p.

walls: water 40 x 40 dp at rest on a wall layer with two dummy layers (the box of cases/hydrostatic.yaml),
  the hydrostatic pressure on fluid and wall particles; the net acceleration (pressure force plus gravity,
  in units of g) of the fluid particles when the dummies push with p = 0 and when each carries the
  pressure of its nearest wall particle (the projection's wall groups).

Usage: projection_lattice.py shear | walls
"""
import sys

import numpy as np


def kernel(kind, r, re):
    """w(r), w'(r), w''(r)."""
    q = r / re
    if kind == "mps":
        return re / r - 1, -re / r**2, 2 * re / r**3
    a = 1 - q
    return a**4 * (1 + 4 * q), -20 * q * a**3 / re, (-20 * a**3 + 60 * q * a**2) / re**2


def lattice_offsets(re):
    m = int(re) + 1
    return np.array([(i, j) for i in range(-m, m + 1) for j in range(-m, m + 1) if 0 < np.hypot(i, j) < re], float)


def shear():
    print("| kernel | re / dp | smallest unconstrained stiffness | at k dp | longitudinal stiffness at k = (pi, 0) |")
    print("|---|---|---|---|---|")
    ks = np.linspace(0, np.pi, 61)
    for kind in ("mps", "wendland"):
        for re in (2.1, 3.1, 4.0):
            offsets = lattice_offsets(re)
            worst, at, longitudinal = np.inf, None, None
            for kx in ks:
                for ky in ks:
                    if kx == 0 and ky == 0:
                        continue
                    k = np.array([kx, ky])
                    D = np.zeros((2, 2))
                    c = np.zeros(2)
                    for r in offsets:
                        d = np.linalg.norm(r)
                        e = r / d
                        _, w1, w2 = kernel(kind, d, re)
                        H = w2 * np.outer(e, e) + (w1 / d) * (np.eye(2) - np.outer(e, e))
                        D += 2 * H * (1 - np.cos(k @ r))  # p_k + p_j = 2 p, p = 1
                        c += w1 * e * np.sin(k @ r)  # the first-order change of n_i
                    if np.linalg.norm(c) < 1e-12:
                        s = np.linalg.eigvalsh(D).min()
                    else:
                        t = np.array([-c[1], c[0]]) / np.linalg.norm(c)
                        s = t @ D @ t
                    if kx == np.pi and ky == 0:
                        longitudinal = D[0, 0]
                    if s < worst:
                        worst, at = s, (kx, ky)
            print(f"| {kind} | {re} | {worst:+.4f} | ({at[0]:.2f}, {at[1]:.2f}) | {longitudinal:.3f} |")


def walls():
    nx = ny = 40
    re = 2.1
    pts, kind = [], []
    for i in range(-3, nx + 3):
        for j in range(-3, 60):
            if 0 <= i < nx and j >= 0:
                if j < ny:
                    pts.append((i + 0.5, j + 0.5))
                    kind.append(0)
                continue
            layer = max(-1 - i if i < 0 else (i - nx if i >= nx else -1), -1 - j if j < 0 else -1)
            pts.append((i + 0.5, j + 0.5))
            kind.append(1 if layer == 0 else 2)
    P, K = np.array(pts), np.array(kind)
    p_hydro = ny - P[:, 1]  # rho = g = dp = 1
    p_hydro[(K == 1) & (P[:, 1] > ny)] = 0
    walls_at = np.where(K == 1)[0]
    parent_p = p_hydro.copy()
    for d in np.where(K == 2)[0]:
        dist = np.linalg.norm(P[walls_at] - P[d], axis=1)
        parent_p[d] = p_hydro[walls_at[np.argmin(dist)]]
    zero_p = p_hydro.copy()
    zero_p[K == 2] = 0
    fluid = np.where(K == 0)[0]
    neighbours = [np.where((np.linalg.norm(P - P[k], axis=1) < re) & (np.arange(len(P)) != k))[0] for k in fluid]
    c = np.median([np.sum(re / np.linalg.norm(P[nb] - P[k], axis=1)) for k, nb in zip(fluid, neighbours)])
    for name, p in (("dummies at p = 0", zero_p), ("dummies carry their wall particle's pressure", parent_p)):
        net = []
        for k, nb in zip(fluid, neighbours):
            r = P[k] - P[nb]
            d = np.linalg.norm(r, axis=1)
            f = ((p[k] + p[nb]) * (-re / d**3))[:, None] * r  # (p_k + p_j) dn_j/dx_k
            net.append(-(2 / c) * f.sum(0) + np.array([0, -1]))
        net = np.array(net)
        print(f"{name}:")
        for y in (0.5, 1.5, 20.5, 37.5, 39.5):
            rows = np.abs(P[fluid, 1] - y) < 1e-9
            side = rows & (np.abs(P[fluid, 0] - 0.5) < 1e-9)
            mid = rows & (np.abs(P[fluid, 0] - 20.5) < 1e-9)
            print(f"  row y = {y:4.1f} dp: largest |a| / g {np.abs(net[rows]).max():.3f}; next to the side wall "
                  f"({net[side][0][0]:+.3f}, {net[side][0][1]:+.3f}); mid-tank ({net[mid][0][0]:+.3f}, {net[mid][0][1]:+.3f})")


if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1] not in ("shear", "walls"):
        sys.exit(__doc__)
    shear() if sys.argv[1] == "shear" else walls()
