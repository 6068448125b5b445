"""Tests of the analytic Lamb's-problem reference (scripts/lamb/lamb2d.py).

Run: python3 -m unittest discover -s tests/lamb -v   (Debian python3 with python3-numpy/-scipy)
"""
import math
import os
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts", "lamb"))
import lamb2d as L  # noqa: E402

MED_A = L.Medium(2611.0, 1846.0, 2200.0)
MED_B = L.Medium(4522.0, 1846.0, 2200.0)


def grid(t_end, dt):
    return np.arange(int(round(t_end / dt)) + 1) * dt


class RayleighSpeed(unittest.TestCase):
    def test_poisson_solid(self):
        # nu = 0.25 (vp = sqrt(3) vs): c_R = sqrt(2 - 2/sqrt(3)) vs = 0.919402 vs (exact root)
        c = L.rayleigh_speed(math.sqrt(3.0), 1.0)
        self.assertAlmostEqual(c, math.sqrt(2.0 - 2.0 / math.sqrt(3.0)), places=12)
        self.assertAlmostEqual(c, 0.9194, places=4)

    def test_models_a_b(self):
        for med, lo, hi in ((MED_A, 0.87, 0.88), (MED_B, 0.94, 0.945)):
            c = L.rayleigh_speed(med.vp, med.vs)
            self.assertTrue(lo < c / med.vs < hi, c / med.vs)
            p = 1.0 / c  # residual of the Rayleigh function in slowness form
            r = (1 / med.vs**2 - 2 * p * p) ** 2 - 4 * p * p * math.sqrt(p * p - 1 / med.vp**2) \
                * math.sqrt(p * p - 1 / med.vs**2)
            self.assertLess(abs(r) * med.vs**4, 1e-10)


class Misfit(unittest.TestCase):
    def test_identical_and_scaled(self):
        t = grid(0.02, 1e-5)
        s = L.SourceTimeFunction("ricker", 300.0).value(t)
        self.assertEqual(L.misfit(s, s), 0.0)
        for a in (0.9, 1.1, 2.0, -1.0):
            self.assertAlmostEqual(L.misfit(a * s, s), (a - 1.0) ** 2, places=12)
        self.assertAlmostEqual(L.misfit(np.zeros_like(s), s), 1.0, places=14)

    def test_errors(self):
        with self.assertRaises(ValueError):
            L.misfit([1.0, 2.0], [1.0])
        with self.assertRaises(ValueError):
            L.misfit([1.0], [0.0])


class SourceTimeFunctions(unittest.TestCase):
    def test_derivatives_and_peak_frequency(self):
        dt = 1e-6
        t = grid(0.02, dt)
        for kind in ("gaussian_derivative", "ricker", "gaussian"):
            stf = L.SourceTimeFunction(kind, 300.0)
            v, d = stf.value(t), stf.derivative(t)
            num = np.gradient(v, dt)
            self.assertLess(np.max(np.abs(num - d)) / np.max(np.abs(d)), 1e-4, kind)
            if kind != "gaussian":
                spec = np.abs(np.fft.rfft(v, 1 << 20))
                f = np.fft.rfftfreq(1 << 20, dt)
                self.assertAlmostEqual(f[np.argmax(spec)], 300.0, delta=1.0)
        gd = L.SourceTimeFunction("gaussian_derivative", 300.0)
        self.assertAlmostEqual(np.max(gd.value(t)), 1.0, places=5)
        self.assertLess(t[np.argmax(gd.value(t))], gd.t0)  # positive lobe first
        self.assertAlmostEqual(gd.t0, 1.5 / 300.0)

    def test_table_equals_analytic(self):
        dt = 2e-5
        t = grid(0.025, dt)
        gd = L.SourceTimeFunction("gaussian_derivative", 300.0)
        tt = grid(0.012, 2e-6)
        tab = L.SourceTimeFunction("table", table=np.column_stack([tt, gd.value(tt)]))
        for src in ("explosion", "force_y"):
            a = L.seismograms_cagniard(MED_A, src, 1.0, [14.0], t, gd)
            b = L.seismograms_cagniard(MED_A, src, 1.0, [14.0], t, tab)
            for ua, ub in zip(a, b):
                self.assertLess(L.misfit(ub[0], ua[0]), 1e-6, src)  # observed ~1e-8


class CagniardVersusWavenumber(unittest.TestCase):
    """The two independent evaluations agree: misfit (eq. 27) < 1e-6, i.e. RMS difference below
    0.1 % of the RMS trace (observed ~1e-10)."""

    def check(self, med, src, h, offsets, t_end, dt, f0):
        t = grid(t_end, dt)
        stf = L.SourceTimeFunction("gaussian_derivative", f0)
        ca = L.seismograms_cagniard(med, src, h, offsets, t, stf)
        wn = L.seismograms_wavenumber(med, src, h, offsets, t, stf)
        worst = 0.0
        for c, w in zip(ca, wn):
            for i in range(len(offsets)):
                self.assertGreater(np.max(np.abs(c[i])), 0.0)
                worst = max(worst, L.misfit(w[i], c[i]))
        self.assertLess(worst, 1e-6, (src, worst))
        return worst

    def test_explosion_case_a(self):
        self.check(MED_A, "explosion", 1.0, [10.0, 38.0], 0.03, 2e-5, 300.0)

    def test_explosion_case_b_400hz(self):
        self.check(MED_B, "explosion", 1.0, [10.0, 38.0], 0.03, 2e-5, 400.0)

    def test_vertical_force(self):
        self.check(MED_B, "force_y", 1.0, [3.0, 26.0], 0.02, 2e-5, 300.0)  # 26 m: S head wave

    def test_horizontal_force_negative_offset(self):
        self.check(MED_A, "force_x", 0.5, [-18.0, 6.0], 0.02, 2e-5, 300.0)


class Reciprocity(unittest.TestCase):
    def test_force_reciprocity(self):
        # G_xy((x,0); (0,-h)) = G_yx((0,-h); (x,0)) = -G_yx((x,-h); (0,0)) (translation + mirror):
        # ux at the surface from an upward force at depth h (Cagniard) equals minus uy at depth h
        # from a +x force at the surface (wavenumber integration, h = 0, receiver depth h).
        h, x = 1.0, 12.0
        t = grid(0.025, 2e-5)
        stf = L.SourceTimeFunction("ricker", 300.0)
        ux, _ = L.seismograms_cagniard(MED_B, "force_y", h, [x], t, stf)
        _, uy = L.seismograms_wavenumber(MED_B, "force_x", 0.0, [x], t, stf, receiver_depth=h)
        self.assertLess(L.misfit(-uy[0], ux[0]), 1e-6)


class ArrivalsAndSigns(unittest.TestCase):
    def test_p_onset(self):
        # the Green's function (second antiderivative K of the impulse response) is zero before
        # t_P = sqrt(x^2 + h^2)/Vp and starts like (t - t_P)^{3/2} (inverse-sqrt impulse response)
        med, h = MED_A, 1.0
        kern = dict(((w, c), (A, s)) for w, c, A, s in L._kernels("explosion", med.vp, med.vs))
        A, _ = kern[("P", "z")]
        for x in (10.0, 38.0):
            tp = math.hypot(x, h) / med.vp
            tg = np.concatenate((np.linspace(0.0, tp * (1 - 1e-9), 1000), tp * (1 + np.array([1e-8, 1e-7]))))
            K = L._second_antiderivative(A, x, h, med.vp, med.vp, tg, 400000)
            self.assertTrue(np.all(K[:-2] == 0.0))
            self.assertNotEqual(K[-2], 0.0)
            slope = math.log(K[-1] / K[-2]) / math.log(10.0)
            self.assertAlmostEqual(slope, 1.5, delta=0.02)

    def test_response_causal(self):
        # nothing before the P wave has travelled (wavelet support ~ t0 +- 4.5 sigma)
        t = grid(0.03, 1e-5)
        stf = L.SourceTimeFunction("gaussian_derivative", 300.0)
        ux, uy = L.seismograms_cagniard(MED_A, "explosion", 1.0, [38.0], t, stf)
        tp = math.hypot(38.0, 1.0) / MED_A.vp
        for u in (ux[0], uy[0]):
            self.assertLess(np.max(np.abs(u[t < tp])), 1e-12 * np.max(np.abs(u)))
            early = t < tp + stf.t0 - 7 * stf.sigma   # wavelet tail there ~ 1e-10
            self.assertLess(np.max(np.abs(u[early])), 1e-8 * np.max(np.abs(u)))

    def test_rayleigh_peak_time(self):
        # at large offset the vertical Rayleigh pulse of the explosion (symmetric for the
        # gaussian-derivative moment, see docs/img/lamb_a_analytic.png) peaks at x/c_R + t0
        med = MED_A
        cr = L.rayleigh_speed(med.vp, med.vs)
        stf = L.SourceTimeFunction("gaussian_derivative", 300.0)
        for x in (100.0, 200.0):
            t = grid(x / cr + 0.012, 2e-5)
            _, uy = L.seismograms_cagniard(med, "explosion", 1.0, [x], t, stf)
            tpk = t[np.argmax(np.abs(uy[0]))] - stf.t0
            self.assertAlmostEqual(tpk, x / cr, delta=3e-3 * x / cr)

    def test_first_motion_signs(self):
        # explosion: surface at the epicentre moves up and points at x > 0 move outward (+x);
        # upward force: epicentre moves up; +x force: ux(x > 0) starts positive (P compression).
        t = grid(0.01, 1e-5)
        stf = L.SourceTimeFunction("gaussian", 1000.0)

        def first(u):
            i = np.argmax(np.abs(u) > 0.05 * np.max(np.abs(u)))
            return np.sign(u[i])

        ux, uy = L.seismograms_cagniard(MED_A, "explosion", 2.0, [0.0, 3.0], t, stf)
        self.assertEqual(first(uy[0]), 1.0)
        self.assertEqual(first(ux[1]), 1.0)
        self.assertLess(np.max(np.abs(ux[0])), 1e-12 * np.max(np.abs(uy[0])))  # symmetry
        _, uy = L.seismograms_cagniard(MED_A, "force_y", 2.0, [0.0], t, stf)
        self.assertEqual(first(uy[0]), 1.0)
        ux, _ = L.seismograms_cagniard(MED_A, "force_x", 2.0, [3.0], t, stf)
        self.assertEqual(first(ux[0]), 1.0)

    def test_mirror_symmetry(self):
        t = grid(0.02, 2e-5)
        stf = L.SourceTimeFunction("ricker", 300.0)
        for src, sx, sy in (("explosion", -1, 1), ("force_y", -1, 1), ("force_x", 1, -1)):
            ux, uy = L.seismograms_cagniard(MED_A, src, 1.0, [-9.0, 9.0], t, stf)
            np.testing.assert_allclose(ux[0], sx * ux[1], atol=1e-14 * np.max(np.abs(ux)))
            np.testing.assert_allclose(uy[0], sy * uy[1], atol=1e-14 * np.max(np.abs(uy)))


class AmplitudeDecay(unittest.TestCase):
    def test_rayleigh_no_geometric_spreading(self):
        # 2D (line source): the Rayleigh-wave peak does not decay with offset
        med = MED_A
        cr = L.rayleigh_speed(med.vp, med.vs)
        stf = L.SourceTimeFunction("gaussian_derivative", 300.0)
        peaks = []
        for x in (50.0, 100.0, 200.0):
            t = grid(x / cr + 0.012, 2e-5)
            win = t > x / cr - 0.004
            ux, uy = L.seismograms_cagniard(med, "force_y", 0.2, [x], t, stf)
            peaks.append((np.max(np.abs(ux[0][win])), np.max(np.abs(uy[0][win]))))
        peaks = np.array(peaks)
        rel = peaks / peaks[0]
        self.assertLess(np.max(np.abs(rel - 1.0)), 0.02, rel)

    def test_body_wave_decay(self):
        # P wave at the epicentre (x = 0) from an explosion at depth h >> wavelength: peak ~ h^-1/2
        med = MED_A
        stf = L.SourceTimeFunction("gaussian_derivative", 300.0)
        peaks = []
        for h in (50.0, 100.0, 200.0):
            t = grid(h / med.vp + 0.012, 1e-5)
            _, uy = L.seismograms_cagniard(med, "explosion", h, [0.0], t, stf)
            peaks.append(np.max(np.abs(uy[0])))
        ratios = np.array(peaks[:-1]) / np.array(peaks[1:])
        np.testing.assert_allclose(ratios, math.sqrt(2.0), rtol=0.02)


class CommandLine(unittest.TestCase):
    def test_cli_csv(self):
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "seis.csv")
            rc = L.main(["--vp", "2611", "--vs", "1846", "--rho", "2200", "--depth", "1", "--f0", "300",
                         "--wavelet", "gaussian_derivative", "--offsets", "10,14", "--t-end", "0.02",
                         "--dt", "2e-5", "--out", out])
            self.assertEqual(rc, 0)
            data = np.loadtxt(out, delimiter=",")
            self.assertEqual(data.shape, (1001, 5))
            with open(out) as f:
                f.readline()
                self.assertEqual(f.readline().strip(), "# t,ux_10,uy_10,ux_14,uy_14")
            t = data[:, 0]
            ux, uy = L.seismograms_cagniard(MED_A, "explosion", 1.0, [10.0, 14.0], t,
                                            L.SourceTimeFunction("gaussian_derivative", 300.0))
            np.testing.assert_allclose(data[:, 3], ux[1], rtol=1e-8, atol=1e-20)
            rc = L.main(["--vp", "2611", "--vs", "1846", "--rho", "2200", "--depth", "1", "--f0", "300",
                         "--offsets", "10", "--t-end", "0.02", "--dt", "2e-5", "--out", out,
                         "--receiver-depth", "1"])
            self.assertEqual(rc, 2)


if __name__ == "__main__":
    unittest.main()
