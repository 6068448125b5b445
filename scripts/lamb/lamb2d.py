#!/usr/bin/env python3
"""Exact 2D (plane-strain) Lamb's problem: line sources in an elastic half-space with a free surface.

Reference solution for seed 000 §3 (issue 6, part 3). Two independent evaluations:

* ``seismograms_cagniard``  -- Cagniard-de Hoop (Garvin 1956 for the explosive source): the impulse
  response is closed form along the Cagniard path; the source time function is convolved with the
  analytically twice-integrated kernel (product integration, exact for piecewise-linear sampling).
  Receivers at the surface (z_r = 0), source at depth h > 0.
* ``seismograms_wavenumber`` -- direct numerical evaluation: direct wave from the closed-form
  full-space Green's function in the Laplace domain (modified Bessel K0, K1), surface reflection by
  a numerically solved 2x2 free-surface system per wavenumber and trapezoidal wavenumber integration,
  complex frequency s = eps + i*omega and FFT back to time. Any source depth h >= 0 and receiver
  depth z_r >= 0 with h + z_r > 0 (so the seed's literal "receivers at 1 m depth" is available).

Conventions (the same for both methods and the CLI):

* 2D plane strain in (x, y): x horizontal, y vertical *up*, free surface y = 0, medium y < 0.
  Source at (0, -h), receivers at (x, -z_r).  Output: ux (positive +x) and uy (positive *up*).
* ``explosion``: isotropic line moment M(t) * delta_ij [N*m/m = N] (equivalent body force
  f = -M grad(delta)); M > 0 pushes the medium outward.  M(t) = M0 * stf(t).
* ``force_y``: line force per unit length F(t) [N/m] in +y (upward), F(t) = F0 * stf(t).
* ``force_x``: line force per unit length F(t) [N/m] in +x.
* stf: ``gaussian_derivative`` s(t) = -sqrt(e) * (tau/sigma) * exp(-tau^2/(2 sigma^2)),
  sigma = 1/(2 pi f0), tau = t - t0 (unit peak, amplitude spectrum peaks at f0, first lobe positive);
  ``ricker`` s(t) = (1 - 2 pi^2 f0^2 tau^2) exp(-pi^2 f0^2 tau^2); ``gaussian``
  s(t) = exp(-tau^2/(2 sigma^2)) (same sigma); ``table``: (time, value) linearly interpolated, zero
  outside.  Default delay t0 = 1.5 / f0.
* Misfit (seed 000 eq. 27): sum_t (S_num - S_ana)^2 / sum_t S_ana^2 (a fraction, not a percentage).
"""
from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass

import numpy as np
from scipy import optimize, special

SOURCES = ("explosion", "force_y", "force_x")
WAVELETS = ("gaussian_derivative", "ricker", "gaussian", "table")


# --------------------------------------------------------------------------------------------
# Medium
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Medium:
    vp: float
    vs: float
    rho: float

    def __post_init__(self):
        if not (self.vp > 0 and self.vs > 0 and self.rho > 0):
            raise ValueError("vp, vs, rho must be positive")
        if not self.vp > self.vs * math.sqrt(4.0 / 3.0):
            raise ValueError("need vp > sqrt(4/3) vs (positive bulk modulus)")

    @property
    def mu(self) -> float:
        return self.rho * self.vs**2

    @property
    def lam(self) -> float:
        return self.rho * (self.vp**2 - 2.0 * self.vs**2)

    @property
    def poisson(self) -> float:
        r2 = (self.vp / self.vs) ** 2
        return (r2 - 2.0) / (2.0 * (r2 - 1.0))


def rayleigh_speed(vp: float, vs: float) -> float:
    """Root c_R < vs of the Rayleigh equation (2 - xi)^2 = 4 sqrt(1 - xi vs^2/vp^2) sqrt(1 - xi),
    xi = c^2/vs^2 (the spurious root xi = 0 is excluded by the bracket)."""
    g = (vs / vp) ** 2

    def f(xi):
        return (2.0 - xi) ** 2 - 4.0 * math.sqrt(1.0 - xi * g) * math.sqrt(1.0 - xi)

    xi = optimize.brentq(f, 1e-6, 1.0, xtol=1e-15, rtol=1e-15, maxiter=200)
    return vs * math.sqrt(xi)


# --------------------------------------------------------------------------------------------
# Source time functions
# --------------------------------------------------------------------------------------------
class SourceTimeFunction:
    """s(t) and ds/dt(t) (vectorised)."""

    def __init__(self, kind: str, f0: float | None = None, t0: float | None = None,
                 table: np.ndarray | None = None):
        if kind not in WAVELETS:
            raise ValueError(f"unknown wavelet '{kind}', expected one of {WAVELETS}")
        self.kind = kind
        if kind == "table":
            tab = np.asarray(table, dtype=float)
            if tab.ndim != 2 or tab.shape[1] != 2 or tab.shape[0] < 2:
                raise ValueError("table must be an (n>=2, 2) array of (time, value)")
            if np.any(np.diff(tab[:, 0]) <= 0):
                raise ValueError("table times must increase strictly")
            self.tab = tab
            self.f0 = f0
            self.t0 = 0.0
        else:
            if f0 is None or not f0 > 0:
                raise ValueError("f0 > 0 required")
            self.f0 = float(f0)
            self.t0 = 1.5 / self.f0 if t0 is None else float(t0)
            self.sigma = 1.0 / (2.0 * math.pi * self.f0)

    def value(self, t):
        t = np.asarray(t, dtype=float)
        if self.kind == "table":
            return np.interp(t, self.tab[:, 0], self.tab[:, 1], left=0.0, right=0.0)
        tau = t - self.t0
        if self.kind == "gaussian_derivative":
            q = tau / self.sigma
            return -math.sqrt(math.e) * q * np.exp(-0.5 * q * q)
        if self.kind == "gaussian":
            q = tau / self.sigma
            return np.exp(-0.5 * q * q)
        a = (math.pi * self.f0 * tau) ** 2  # ricker
        return (1.0 - 2.0 * a) * np.exp(-a)

    def derivative(self, t):
        t = np.asarray(t, dtype=float)
        if self.kind == "table":
            tt, vv = self.tab[:, 0], self.tab[:, 1]
            slope = np.diff(vv) / np.diff(tt)
            # piecewise-constant slope of the piecewise-linear table (zero outside)
            idx = np.searchsorted(tt, t, side="right") - 1
            out = np.zeros_like(t)
            inside = (idx >= 0) & (idx < len(slope))
            out[inside] = slope[idx[inside]]
            # jumps at the ends when the table does not start/end at zero are ignored
            return out
        tau = t - self.t0
        if self.kind == "gaussian_derivative":
            q = tau / self.sigma
            return -math.sqrt(math.e) / self.sigma * (1.0 - q * q) * np.exp(-0.5 * q * q)
        if self.kind == "gaussian":
            q = tau / self.sigma
            return -q / self.sigma * np.exp(-0.5 * q * q)
        w2 = (math.pi * self.f0) ** 2
        a = w2 * tau * tau
        return tau * w2 * (4.0 * a - 6.0) * np.exp(-a)


def load_table(path: str) -> np.ndarray:
    data = np.loadtxt(path, delimiter=None if not path.endswith(".csv") else ",", comments="#")
    return np.atleast_2d(data)[:, :2]


# --------------------------------------------------------------------------------------------
# Misfit (seed 000 eq. 27)
# --------------------------------------------------------------------------------------------
def misfit(s_num, s_ana) -> float:
    """Seed 000 eq. 27: sum_t (S_num(t) - S_ana(t))^2 / sum_t S_ana(t)^2 (same time samples)."""
    s_num = np.asarray(s_num, dtype=float)
    s_ana = np.asarray(s_ana, dtype=float)
    if s_num.shape != s_ana.shape:
        raise ValueError(f"shape mismatch {s_num.shape} vs {s_ana.shape}")
    den = float(np.sum(s_ana**2))
    if den == 0.0:
        raise ValueError("analytic trace is identically zero")
    return float(np.sum((s_num - s_ana) ** 2)) / den


# --------------------------------------------------------------------------------------------
# Cagniard-de Hoop (surface receivers)
# --------------------------------------------------------------------------------------------
def _eta(p, c):
    """Vertical slowness sqrt(1/c^2 - p^2) with Re >= 0 for Im p >= 0 (upper-side limit on the
    real axis beyond 1/c: -i sqrt(p^2 - 1/c^2))."""
    p = np.asarray(p, dtype=complex)
    return -1j * np.sqrt(p * p - 1.0 / c**2)


def _kernels(source: str, vp: float, vs: float):
    """Terms (wave, component, A(p), scale) of the Laplace-domain surface displacement
    (z downward, force along +z = down for 'force_z_down'):
        u_comp(s) = scale * s^n * (1/2 pi i) int A(p) exp(-s (p x + eta_wave h)) dp.
    Returns list of (wave, comp, A, order) with scale applied separately by the caller."""
    b2 = 1.0 / vs**2

    def R(p, ea, eb):
        chi = b2 - 2.0 * p * p
        return chi * chi + 4.0 * p * p * ea * eb

    def mk(f):
        def A(p):
            ea, eb = _eta(p, vp), _eta(p, vs)
            chi = b2 - 2.0 * p * p
            return f(p, ea, eb, chi) / R(p, ea, eb)
        return A

    if source == "explosion":
        # u_x = +1/(rho a^2 b^2) Mdot * I_P[2 p eta_b / R]; u_z(down) = -1/(rho a^2 b^2) Mdot * I_P[chi/R]
        return [("P", "x", mk(lambda p, ea, eb, chi: 2.0 * p * eb), +1.0),
                ("P", "z", mk(lambda p, ea, eb, chi: chi), -1.0)]
    if source == "force_z_down":
        return [("P", "x", mk(lambda p, ea, eb, chi: 2.0 * p * ea * eb), -1.0),
                ("S", "x", mk(lambda p, ea, eb, chi: p * chi), +1.0),
                ("P", "z", mk(lambda p, ea, eb, chi: ea * chi), +1.0),
                ("S", "z", mk(lambda p, ea, eb, chi: 2.0 * p * p * ea), +1.0)]
    if source == "force_x":
        return [("P", "x", mk(lambda p, ea, eb, chi: 2.0 * p * p * eb), +1.0),
                ("S", "x", mk(lambda p, ea, eb, chi: eb * chi), +1.0),
                ("P", "z", mk(lambda p, ea, eb, chi: -p * chi), +1.0),
                ("S", "z", mk(lambda p, ea, eb, chi: 2.0 * p * ea * eb), +1.0)]
    raise ValueError(source)


def _cagniard_path(x, h, c, vp, t_max, n_nodes):
    """Nodes (t, p) of the Cagniard path tau(p) = p x + eta_c(p) h = t, Im p >= 0, for x >= 0, h > 0,
    from the first time at which Im A dp/dt can be non-zero up to t_max.  For an S path with
    x/R > vs/vp the head-wave segment on the real axis, p in [1/vp, p0], is included."""
    R = math.hypot(x, h)
    t0 = R / c
    segs_t, segs_p = [], []
    p0 = x / (R * c)
    if c < vp and p0 > 1.0 / vp:  # head wave (S path only)
        m = max(200, n_nodes // 4)
        v = np.linspace(0.0, 1.0, m)
        pr = 1.0 / vp + (p0 - 1.0 / vp) * (1.0 - (1.0 - v) ** 2)
        pr = np.minimum(pr, p0)
        tr = pr * x + np.sqrt(np.maximum(1.0 / c**2 - pr * pr, 0.0)) * h
        tr = np.maximum.accumulate(tr)
        segs_t.append(tr[:-1])
        segs_p.append(pr[:-1].astype(complex))
    if t_max > t0:
        u = np.linspace(0.0, math.sqrt(t_max - t0), n_nodes)
        t = t0 + u * u
        sq = np.sqrt(np.maximum(t * t - t0 * t0, 0.0))
        p = (x * t + 1j * h * sq) / (R * R)
        segs_t.append(t)
        segs_p.append(p)
    if not segs_t:
        return np.empty(0), np.empty(0, dtype=complex)
    return np.concatenate(segs_t), np.concatenate(segs_p)


def _second_antiderivative(A, x, h, c, vp, t_grid, n_nodes):
    """K(t_grid) = int_0^t int_0^t' I(t'') dt'' dt' with I(t) = (1/pi) Im[A(p) dp/dt] on the path.
    J(t) = (1/pi) Im int_path A dp is evaluated by the trapezoidal rule in p (A is bounded on the
    path; the inverse-square-root singularities of I at the arrivals sit in dp/dt only)."""
    t_max = float(t_grid[-1])
    t, p = _cagniard_path(x, h, c, vp, t_max, n_nodes)
    K = np.zeros_like(t_grid, dtype=float)
    if t.size < 2:
        return K
    a = A(p)
    dJ = 0.5 * (a[1:] + a[:-1]) * np.diff(p)
    J = np.concatenate(([0.0], np.cumsum(dJ).imag / math.pi))
    Kn = np.concatenate(([0.0], np.cumsum(0.5 * (J[1:] + J[:-1]) * np.diff(t))))
    m = t_grid > t[0]
    K[m] = np.interp(t_grid[m], t, Kn)
    return K


def _product_weights(K, dt):
    """w_j = int hat_j(tau) I(tau) dtau = (K_{j+1} - 2 K_j + K_{j-1})/dt, hat functions on the
    grid; then (f * I)(t_n) = sum_j f(t_n - t_j) w_j exactly for piecewise-linear f.
    K holds K(t_0 .. t_n); returns w_0 .. w_{n-1}."""
    Kp = np.concatenate(([0.0], K))  # K(-dt) = 0
    return (Kp[2:] - 2.0 * Kp[1:-1] + Kp[:-2]) / dt


def _causal_convolve(f, w):
    n = len(f)
    nfft = 1 << int(math.ceil(math.log2(2 * n)))
    return np.fft.irfft(np.fft.rfft(f, nfft) * np.fft.rfft(w, nfft), nfft)[:n]


def seismograms_cagniard(medium: Medium, source: str, depth: float, offsets, t, stf,
                         amplitude: float = 1.0, oversample: int = 4, nodes_per_dt: int = 40):
    """Surface displacement (ux, uy_up), arrays (n_offsets, n_t), by Cagniard-de Hoop.
    t must be uniform, starting at 0.  depth > 0."""
    if source not in SOURCES:
        raise ValueError(f"unknown source '{source}'")
    if not depth > 0:
        raise ValueError("Cagniard evaluation needs depth > 0 (use the wavenumber method for h=0)")
    t = np.asarray(t, dtype=float)
    dt = float(t[1] - t[0])
    if abs(t[0]) > 1e-12 * dt or np.max(np.abs(np.diff(t) - dt)) > 1e-6 * dt:
        raise ValueError("t must be uniform and start at 0")
    vp, vs, rho = medium.vp, medium.vs, medium.rho
    ov = max(1, int(oversample))
    dtf = dt / ov
    nf = (len(t) - 1) * ov + 2
    tf = np.arange(nf) * dtf
    tk = np.arange(nf + 1) * dtf         # one more node for the last hat-function weight
    internal = "force_z_down" if source == "force_y" else source
    kern = _kernels(internal, vp, vs)
    differentiate = False
    if source == "explosion":
        # u = d/dt (M * I): Mdot * I for analytic wavelets, numerical d/dt of M * I for tables
        differentiate = stf.kind == "table"
        f = stf.value(tf) if differentiate else stf.derivative(tf)
        scale = amplitude / (rho * vp**2 * vs**2)
    else:
        f = stf.value(tf)
        scale = amplitude / (rho * vs**2)
    if source == "force_y":
        scale = -scale                   # force up = -(force down)
    n_nodes = int(nodes_per_dt * t[-1] / dt) + 2000
    # resolve the Rayleigh pulse of the kernel (time width ~ h sqrt(1/c_R^2 - 1/vp^2)) with
    # >= 20 nodes: node spacing at the end of the path is 2 t_end / n_nodes
    cr = rayleigh_speed(vp, vs)
    width = depth * math.sqrt(1.0 / cr**2 - 1.0 / vp**2)
    n_nodes = int(min(max(n_nodes, 40.0 * t[-1] / width), 4e6))
    offsets = np.atleast_1d(np.asarray(offsets, dtype=float))
    ux = np.zeros((len(offsets), len(t)))
    uz = np.zeros((len(offsets), len(t)))
    for i, x in enumerate(offsets):
        ax = abs(x)
        acc = {"x": np.zeros(nf), "z": np.zeros(nf)}
        for wave, comp, A, sgn in kern:
            c = vp if wave == "P" else vs
            K = _second_antiderivative(A, ax, depth, c, vp, tk, n_nodes)
            acc[comp] += sgn * _product_weights(K, dtf)
        gx = _causal_convolve(f, acc["x"])
        gz = _causal_convolve(f, acc["z"])
        if differentiate:
            gx, gz = np.gradient(gx, dtf), np.gradient(gz, dtf)
        gx = gx[::ov][: len(t)] * scale
        gz = gz[::ov][: len(t)] * scale
        if x < 0:  # mirror: ux odd for explosion/force_y, uz odd for force_x
            if source == "force_x":
                gz = -gz
            else:
                gx = -gx
        ux[i] = gx
        uz[i] = -gz                      # z down -> y up
    return ux, uz


# --------------------------------------------------------------------------------------------
# Independent check: Laplace-wavenumber integration
# --------------------------------------------------------------------------------------------
def _direct_fullspace(medium, source, s, X, Z, amp_spec):
    """Full-space displacement (u_x, u_z with z down) at offsets (X, Z) from the source, Laplace
    domain, closed form with K0/K1.  s: (nf,1); X, Z: (1, nr)."""
    vp, vs, rho = medium.vp, medium.vs, medium.rho
    R = np.sqrt(X * X + Z * Z)
    nx, nz = X / R, Z / R

    def g_derivs(c):
        a = s / c
        z = a * R
        e = np.exp(-z)
        k0 = special.kve(0, z) * e
        k1 = special.kve(1, z) * e
        g = -k0 / (2 * np.pi)
        g1 = a * k1 / (2 * np.pi)
        g2 = -a * a * (k0 + k1 / z) / (2 * np.pi)
        return g, g1, g2

    if source == "explosion":
        _, g1, _ = g_derivs(vp)
        q = amp_spec / (rho * vp**2)
        return q * g1 * nx, q * g1 * nz
    e = (0.0, -1.0) if source == "force_y" else (1.0, 0.0)   # (e_x, e_z), z down
    ga, ga1, ga2 = g_derivs(vp)
    gb, gb1, gb2 = g_derivs(vs)
    n = (nx, nz)

    def dd(g1, g2, i, j):
        dij = 1.0 if i == j else 0.0
        return g2 * n[i] * n[j] + g1 / R * (dij - n[i] * n[j])

    pre = -amp_spec / (rho * s * s)
    out = []
    for i in range(2):
        acc = 0.0
        for j in range(2):
            if e[j] == 0.0:
                continue
            dij = 1.0 if i == j else 0.0
            acc = acc + e[j] * (dd(ga1, ga2, i, j) - dd(gb1, gb2, i, j) + dij * (s / vs) ** 2 * gb)
        out.append(pre * acc)
    return out[0], out[1]


def _reflected_k(medium, source, s, k, h, zr):
    """Surface-reflected field at depth zr (z down) per wavenumber: incident potentials at z = 0,
    reflected amplitudes from the numerically solved free-surface conditions.  s (nf,1), k (1,nk)."""
    vp, vs, rho = medium.vp, medium.vs, medium.rho
    lam, mu = medium.lam, medium.mu
    ik = 1j * k
    na = np.sqrt(k * k + (s / vp) ** 2)
    nb = np.sqrt(k * k + (s / vs) ** 2)
    if source == "explosion":
        a0 = -np.exp(-na * h) / (2.0 * na) / (rho * vp**2)
        b0 = np.zeros_like(a0)
    else:
        ex, ez = (0.0, -1.0) if source == "force_y" else (1.0, 0.0)
        pre = 1.0 / (2.0 * rho * s * s)
        a0 = pre * (ik * ex + na * ez) * np.exp(-na * h) / na
        b0 = pre * (ik * ez - nb * ex) * np.exp(-nb * h) / nb

    def trac_P(m):
        return lam * (ik * ik + m * m) + 2 * mu * m * m, 2 * mu * ik * m

    def trac_S(m):
        return 2 * mu * ik * m, -mu * (m * m + k * k)

    szz_pi, sxz_pi = trac_P(na)
    szz_si, sxz_si = trac_S(nb)
    szz_pr, sxz_pr = trac_P(-na)
    szz_sr, sxz_sr = trac_S(-nb)
    M = np.empty(a0.shape + (2, 2), dtype=complex)
    M[..., 0, 0], M[..., 0, 1] = szz_pr, szz_sr
    M[..., 1, 0], M[..., 1, 1] = sxz_pr, sxz_sr
    rhs = -np.stack([szz_pi * a0 + szz_si * b0, sxz_pi * a0 + sxz_si * b0], axis=-1)
    sol = np.linalg.solve(M, rhs[..., None])[..., 0]
    A, B = sol[..., 0], sol[..., 1]
    ea, eb = np.exp(-na * zr), np.exp(-nb * zr)
    ux = ik * A * ea + nb * B * eb
    uz = -na * A * ea + ik * B * eb
    return ux, uz


def seismograms_wavenumber(medium: Medium, source: str, depth: float, offsets, t, stf,
                           amplitude: float = 1.0, receiver_depth: float = 0.0, pad: int = 4,
                           eps_T: float = 7.0, dk: float | None = None, spec_tol: float = 1e-8,
                           chunk: int = 16):
    """Displacement (ux, uy_up), arrays (n_offsets, n_t), at receivers (x, -receiver_depth) by
    numerical Laplace-wavenumber integration (independent of the Cagniard evaluation)."""
    if source not in SOURCES:
        raise ValueError(f"unknown source '{source}'")
    h, zr = float(depth), float(receiver_depth)
    if h < 0 or zr < 0 or h + zr <= 0:
        raise ValueError("need depth >= 0, receiver_depth >= 0, depth + receiver_depth > 0")
    t = np.asarray(t, dtype=float)
    dt = float(t[1] - t[0])
    n = len(t)
    nfft = 1 << int(math.ceil(math.log2(pad * n)))
    T = nfft * dt
    eps = eps_T / T
    tt = np.arange(nfft) * dt
    damp = np.exp(-eps * tt)
    S = np.fft.rfft(stf.value(tt) * damp) * dt * amplitude
    freqs = np.fft.rfftfreq(nfft, dt)
    keep = np.nonzero(np.abs(S) > spec_tol * np.abs(S).max())[0]
    nkeep = keep[-1] + 1
    s_all = eps + 2j * np.pi * freqs[:nkeep]
    offsets = np.atleast_1d(np.asarray(offsets, dtype=float))
    xmax = float(np.max(np.abs(offsets)))
    cr = rayleigh_speed(medium.vp, medium.vs)
    if dk is None:
        L = max(xmax + 1.5 * medium.vp * t[-1], 6.0 * math.pi * cr / eps)
        dk = min(2 * np.pi / L, eps / (4.0 * cr))
    kmax = 1.3 * 2 * np.pi * freqs[nkeep - 1] / (0.8 * medium.vs) + 36.0 / (h + zr)
    nk = int(math.ceil(kmax / dk))
    k = (np.arange(-nk, nk + 1) * dk)[None, :]
    E = np.exp(1j * k.T * offsets[None, :]) * dk / (2 * np.pi)      # (nk, nr)
    X = offsets[None, :]
    Z = np.full_like(X, zr - h)
    Ux = np.zeros(len(freqs), dtype=complex)[:, None].repeat(len(offsets), 1)
    Uz = np.zeros_like(Ux)
    with np.errstate(over="ignore", invalid="ignore", under="ignore"):
        for i0 in range(0, nkeep, chunk):
            i1 = min(i0 + chunk, nkeep)
            s = s_all[i0:i1, None]
            rx, rz = _reflected_k(medium, source, s, k, h, zr)
            rx = np.nan_to_num(rx)
            rz = np.nan_to_num(rz)
            dx, dz = _direct_fullspace(medium, source, s, X, Z, 1.0)
            Ux[i0:i1] = (rx @ E + dx) * S[i0:i1, None]
            Uz[i0:i1] = (rz @ E + dz) * S[i0:i1, None]
    ux = (np.fft.irfft(Ux, nfft, axis=0)[:n] / dt * np.exp(eps * t)[:, None]).T
    uz = (np.fft.irfft(Uz, nfft, axis=0)[:n] / dt * np.exp(eps * t)[:, None]).T
    return ux, -uz


# --------------------------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------------------------
def _parse_offsets(text: str):
    vals = [float(v) for v in text.split(",") if v.strip()]
    if not vals:
        raise argparse.ArgumentTypeError("empty offsets")
    return vals


def build_parser():
    ap = argparse.ArgumentParser(
        description="Exact 2D Lamb's problem (line source in a half-space): displacement seismograms.")
    ap.add_argument("--vp", type=float, required=True, help="P-wave speed [m/s]")
    ap.add_argument("--vs", type=float, required=True, help="S-wave speed [m/s]")
    ap.add_argument("--rho", type=float, required=True, help="density [kg/m3]")
    ap.add_argument("--depth", type=float, required=True, help="source depth h [m]")
    ap.add_argument("--receiver-depth", type=float, default=0.0,
                    help="receiver depth [m] (> 0 only with --method wavenumber)")
    ap.add_argument("--source", choices=SOURCES, default="explosion")
    ap.add_argument("--amplitude", type=float, default=1.0,
                    help="M0 [N*m/m] for explosion, F0 [N/m] for forces (default 1)")
    ap.add_argument("--wavelet", choices=WAVELETS, default="gaussian_derivative")
    ap.add_argument("--f0", type=float, help="central frequency [Hz]")
    ap.add_argument("--t0", type=float, help="wavelet delay [s] (default 1.5/f0)")
    ap.add_argument("--table", help="(time, value) file for --wavelet table")
    ap.add_argument("--offsets", type=_parse_offsets, required=True, help="comma-separated x [m]")
    ap.add_argument("--t-end", type=float, required=True, help="last time [s]")
    ap.add_argument("--dt", type=float, required=True, help="sample interval [s]")
    ap.add_argument("--method", choices=("cagniard", "wavenumber"), default="cagniard")
    ap.add_argument("--out", required=True, help="CSV: t, ux_<x>, uy_<x> ... (uy positive up)")
    return ap


def main(argv=None):
    args = build_parser().parse_args(argv)
    try:
        med = Medium(args.vp, args.vs, args.rho)
        if args.wavelet == "table":
            if not args.table:
                raise ValueError("--wavelet table needs --table FILE")
            stf = SourceTimeFunction("table", table=load_table(args.table))
        else:
            stf = SourceTimeFunction(args.wavelet, args.f0, args.t0)
        if not (args.dt > 0 and args.t_end > args.dt):
            raise ValueError("need 0 < dt < t-end")
        t = np.arange(int(round(args.t_end / args.dt)) + 1) * args.dt
        if args.method == "cagniard":
            if args.receiver_depth != 0.0:
                raise ValueError("--receiver-depth needs --method wavenumber")
            ux, uy = seismograms_cagniard(med, args.source, args.depth, args.offsets, t, stf,
                                          args.amplitude)
        else:
            ux, uy = seismograms_wavenumber(med, args.source, args.depth, args.offsets, t, stf,
                                            args.amplitude, receiver_depth=args.receiver_depth)
    except ValueError as exc:
        print(f"lamb2d: error: {exc}", file=sys.stderr)
        return 2
    cols = [t]
    names = ["t"]
    for i, x in enumerate(args.offsets):
        cols += [ux[i], uy[i]]
        names += [f"ux_{x:g}", f"uy_{x:g}"]
    header = (f"Lamb 2D {args.method}: source={args.source} amplitude={args.amplitude} "
              f"vp={args.vp} vs={args.vs} rho={args.rho} h={args.depth} zr={args.receiver_depth} "
              f"wavelet={args.wavelet} f0={args.f0} t0={stf.t0}; ux +x, uy +up [m]\n"
              + ",".join(names))
    np.savetxt(args.out, np.column_stack(cols), delimiter=",", header=header, fmt="%.10e")
    return 0


if __name__ == "__main__":
    sys.exit(main())
