#!/usr/bin/python3
"""Reference C: frequencies of a uniform cantilever spinning in its own plane (issue 14, acceptance 2).

Model (rotating frame, hub radius 0, clamped at the rotation axis x = 0, free at x = L):
    EI w'''' - (N w')' - s rhoA Omega^2 w + rhoA w_tt = 0,   N(x) = rhoA Omega^2 (L^2 - x^2)/2
with s = 1 for in-plane (lead-lag) bending, whose rotating frame adds the centrifugal
softening -rhoA Omega^2 w, and s = 0 for out-of-plane (flapwise) bending. In the
dimensionless form (x/L, gamma = Omega sqrt(rhoA L^4/EI), wbar = omega sqrt(rhoA L^4/EI))
    w'''' - gamma^2 ((1 - x^2)/2 w')' - s gamma^2 w = wbar^2 w,
so wbar_flap^2 = wbar_inplane^2 + gamma^2 exactly (same operator). Without the stiffening
term (N = 0), in-plane: wbar^2 = wbar0^2 - gamma^2 exactly (wbar0: non-rotating
cantilever); negative means the mode is statically unstable (it diverges).
Boundary: w = w' = 0 at 0; w'' = 0 and w''' - n w' = w''' = 0 at 1 (n(1) = 0).

Method 1 (the reference, column wbar_inplane): power series in mpmath (50 digits). With
lam = wbar^2 + s gamma^2 the coefficients of w = sum a_k x^k obey
    (k+1)(k+2)(k+3)(k+4) a_{k+4} = gamma^2/2 (k+1)(k+2) a_{k+2} + (lam - gamma^2 k(k+1)/2) a_k,
a_0 = a_1 = 0 (clamped), a_2, a_3 free. The series is entire (polynomial coefficients);
the 2x2 determinant of (w''(1), w'''(1)) in (a_2, a_3) is the characteristic function,
roots bracketed by a scan and polished by Anderson's method. Recomputed with 70 digits
and 300 terms: agreement < 1e-40; the CSV value is exact to the double's rounding.

Method 2 (column wbar_shoot): shooting with scipy's solve_ivp (DOP853, rtol 1e-13,
atol 1e-16) on (w, w', w'', S = w''' - n w'), S' = lam w; brentq on the 2x2 determinant.
Measured agreement with method 1: column rel_shoot (<= 3.1e-13).

Method 3 (column wbar_pfem): p-version FE Rayleigh-Ritz (own code, beam_pfem.py) with the
geometric stiffness int n w' dw' and the softening -s gamma^2 int w dw, 4 elements,
degree p = 24; convergence p = 8..24 printed. Measured agreement: column rel_pfem
(<= 1.9e-14).

Also: wbar0 (gamma = 0) gives the no-stiffening column wbar2_nostiff = wbar0^2 - gamma^2,
and wbar_flap = sqrt(wbar_inplane^2 + gamma^2), which is checked against a direct power-
series solution with s = 0 (agreement printed, < 1e-30) and against the published
flapwise tables (see tests/reference/README.md).

Run: python3 scripts/reference/rotating_cantilever_frequencies.py
Writes tests/reference/rotating_cantilever_frequencies.csv with columns gamma, mode,
wbar_inplane, wbar_flap, wbar2_nostiff, wbar_shoot, rel_shoot, wbar_pfem, rel_pfem (all
dimensionless: divide by sqrt(rhoA L^4/EI) for rad/s). Run time: ~70 s.
"""
import os

import reexec  # noqa: F401  (first: may re-run this script with Debian's python3)
import numpy as np
import mpmath as mp
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import beam_pfem  # the script's folder is on sys.path
import mp_roots

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "..", "tests", "reference", "rotating_cantilever_frequencies.csv")

GAMMAS = [0, 1, 2, 5, 10]
NMODES = 3


# ---------------------------------------------------------------- method 1
def series_det(wbar, gamma, s, nterms):
    g2 = mp.mpf(gamma) ** 2
    lam = wbar**2 + s * g2
    ends = []
    for start in (2, 3):
        a = [mp.mpf(0)] * (nterms + 4)
        a[start] = mp.mpf(1)
        for k in range(nterms):
            a[k + 4] = (g2 / 2 * (k + 1) * (k + 2) * a[k + 2]
                        + (lam - g2 * k * (k + 1) / 2) * a[k]) / ((k + 1) * (k + 2) * (k + 3) * (k + 4))
        w2 = mp.fsum(k * (k - 1) * a[k] for k in range(2, nterms + 4))
        w3 = mp.fsum(k * (k - 1) * (k - 2) * a[k] for k in range(3, nterms + 4))
        ends.append((w2, w3))
    return ends[0][0] * ends[1][1] - ends[0][1] * ends[1][0]


def roots_series(gamma, s, count, dps, nterms):
    with mp.workdps(dps):
        f = lambda w: series_det(w, gamma, s, nterms)
        return mp_roots.bracketed_roots(f, count, "0.3", "0.02")


# ---------------------------------------------------------------- method 2
def shoot_det(wbar, gamma, s):
    g2 = gamma**2
    lam = wbar**2 + s * g2

    def rhs(x, y):
        n = 0.5 * g2 * (1 - x * x)
        return [y[1], y[2], y[3] + n * y[1], lam * y[0]]

    ends = []
    for y0 in ([0, 0, 1.0, 0], [0, 0, 0, 1.0]):
        sol = solve_ivp(rhs, (0.0, 1.0), y0, method="DOP853", rtol=1e-13, atol=1e-16)
        ends.append(sol.y[:, -1])
    a, b = ends
    return a[2] * b[3] - a[3] * b[2]


def roots_shoot(gamma, s, guesses):
    return [brentq(shoot_det, g * (1 - 1e-6), g * (1 + 1e-6), args=(gamma, s),
                   xtol=1e-14, rtol=1e-15) for g in guesses]


# ---------------------------------------------------------------- method 3
def pfem(gamma, s, p):
    g2 = float(gamma) ** 2
    one = lambda x: np.ones_like(x)
    N = lambda x: 0.5 * g2 * (1 - x * x)
    K, M = beam_pfem.assemble(np.linspace(0, 1, 5), p, one, one, N=N, soft=s * g2,
                              clamped_left=True)
    return np.sqrt(beam_pfem.eigenvalues(K, M, NMODES))


def main():
    rows = []
    w0 = None
    for gamma in GAMMAS:
        r50 = roots_series(gamma, 1, NMODES, 50, 220)
        r70 = roots_series(gamma, 1, NMODES, 70, 300)
        dev = max(abs(a / b - 1) for a, b in zip(r50, r70))
        with mp.workdps(70):
            flap_direct = roots_series(gamma, 0, NMODES, 70, 300)
            flap = [mp.sqrt(r**2 + gamma**2) for r in r70]
            dflap = max(abs(a / b - 1) for a, b in zip(flap, flap_direct))
        if gamma == 0:
            w0 = r70
        print("gamma = %g: series 50/220 vs 70/300 differ by %s; flap direct vs "
              "sqrt(inplane^2 + gamma^2) by %s" % (gamma, mp.nstr(dev, 3), mp.nstr(dflap, 3)))
        ref = [float(r) for r in r70]
        sh = roots_shoot(float(gamma), 1, ref)
        print("  p-FE convergence (relative to method 1):")
        for p in (8, 12, 16, 20, 24):
            w = pfem(gamma, 1, p)
            print("   p=%2d  " % p + " ".join("%.1e" % abs(w[i] / ref[i] - 1) for i in range(NMODES)))
        wp = pfem(gamma, 1, 24)
        for i in range(NMODES):
            nostiff = float(w0[i] ** 2 - gamma**2)
            rs = sh[i] / ref[i] - 1
            rp = wp[i] / ref[i] - 1
            rows.append((gamma, i + 1, ref[i], float(flap[i]), nostiff, sh[i], rs, wp[i], rp))
            print("  mode %d in-plane %s flap %s nostiff wbar^2 %.10g; shoot %.1e p-FE %.1e"
                  % (i + 1, mp.nstr(r70[i], 16), mp.nstr(flap[i], 16), nostiff, rs, rp))
    with open(OUT, "w") as fh:
        fh.write("gamma,mode,wbar_inplane,wbar_flap,wbar2_nostiff,wbar_shoot,rel_shoot,wbar_pfem,rel_pfem\n")
        for r in rows:
            fh.write("%d,%d,%r,%r,%r,%r,%.2e,%r,%.2e\n" % (r[0], r[1], r[2], r[3], r[4], float(r[5]), r[6],
                                                         float(r[7]), r[8]))
    print("wrote", os.path.normpath(OUT))


if __name__ == "__main__":
    main()
