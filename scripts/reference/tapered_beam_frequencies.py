#!/usr/bin/python3
"""Reference B: elastic frequencies of a linearly tapered free-free beam (issue 15, acceptance 3).

Beam: L = 1 m, mass per length m(x) = 1.2 - 0.8 x kg/m (1.2 at the left end, 0.4 at the
right), bending stiffness EI(x) = 2.0 - 1.5 x N m^2 (2.0 to 0.5), x in metres from the
left end. Cases: tapered_bare, and tapered_tip with a point mass 0.05 kg (no rotary
inertia) at the right end x = 1. First five elastic frequencies omega (rad/s).

Free vibration: (EI w'')'' = m omega^2 w; free ends: M = EI w'' = 0 and Q = (EI w'')' = 0,
except at a tip mass, where Q(L) = -m_tip omega^2 w(L) (the mass's inertia force).

Method 1 (the reference, column omega_rad_s): power series in mpmath (60 digits). The
coefficients are linear, so about the mid-point t = x - 0.5 the pair w, M = EI w'' has
the recurrences
    (k+2)(k+1) M_{k+2} = omega^2 (m0 w_k + m1 w_{k-1})
    a0 (k+2)(k+1) w_{k+2} + a1 (k+1) k w_{k+1} = M_k
(EI = a0 + a1 t, m = m0 + m1 t). The series converge for |t| < a0/|a1| = 0.833 (where
EI would vanish), so at |t| = 0.5 the terms fall like 0.6^k; 260 terms leave < 1e-50.
The 4x4 determinant of the four end conditions in the four free coefficients
(w0, w1, M0, M1) is the characteristic function; its roots (after the double root at
omega = 0 of the rigid modes) are bracketed by a scan and polished with mpmath's
Anderson solver. Repeated with 80 digits and 360 terms: agreement < 1e-40, so the CSV
value is exact to the double's rounding.

Method 2 (column omega_shoot_rad_s): shooting with scipy's solve_ivp (DOP853,
rtol = 1e-13, atol = 1e-16) on the first-order system (w, w', M, Q) from the left free
end, two starts (w = 1 and w' = 1); the 2x2 determinant of the right-end conditions is
zeroed by brentq (xtol 1e-14). Agreement with method 1: column rel_shoot, measured
<= 1.7e-10 (mode 5 with the tip mass; <= 1.2e-11 otherwise): the adaptive steps make the
determinant slightly noisy in omega.

Method 3 (column omega_pfem_rad_s): p-version FE Rayleigh-Ritz (own code, beam_pfem.py),
4 equal elements, degree p; converged value at p = 24; the convergence table p = 8..24
is printed. Agreement with method 1: column rel_pfem, measured <= 2e-15.

Run: python3 scripts/reference/tapered_beam_frequencies.py
Writes tests/reference/tapered_beam_frequencies.csv (columns: case, mode, omega_rad_s,
omega_shoot_rad_s, rel_shoot, omega_pfem_rad_s, rel_pfem). Run time: ~80 s.
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
OUT = os.path.join(HERE, "..", "..", "tests", "reference", "tapered_beam_frequencies.csv")

L = 1.0
M_LEFT, M_RIGHT = 1.2, 0.4
EI_LEFT, EI_RIGHT = 2.0, 0.5
CASES = {"tapered_bare": 0.0, "tapered_tip": 0.05}
NMODES = 5


def m_of(x):
    return M_LEFT + (M_RIGHT - M_LEFT) * x / L


def EI_of(x):
    return EI_LEFT + (EI_RIGHT - EI_LEFT) * x / L


# ---------------------------------------------------------------- method 1
def series_det(omega, m_tip, nterms):
    half = mp.mpf(L) / 2
    a0 = mp.mpf(EI_LEFT) + (mp.mpf(EI_RIGHT) - EI_LEFT) / 2
    a1 = (mp.mpf(EI_RIGHT) - EI_LEFT) / L
    m0 = mp.mpf(M_LEFT) + (mp.mpf(M_RIGHT) - M_LEFT) / 2
    m1 = (mp.mpf(M_RIGHT) - M_LEFT) / L
    w2 = omega**2
    cols = []
    for start in range(4):        # unit value of w0, w1, M0, M1 in turn
        w = [mp.mpf(0)] * (nterms + 3)
        M = [mp.mpf(0)] * (nterms + 3)
        if start == 0:
            w[0] = mp.mpf(1)
        elif start == 1:
            w[1] = mp.mpf(1)
        elif start == 2:
            M[0] = mp.mpf(1)
        else:
            M[1] = mp.mpf(1)
        for k in range(nterms):
            M[k + 2] = w2 * (m0 * w[k] + (m1 * w[k - 1] if k >= 1 else 0)) / ((k + 2) * (k + 1))
            w[k + 2] = (M[k] - a1 * (k + 1) * k * w[k + 1]) / (a0 * (k + 2) * (k + 1))
        vals = []
        for t in (-half, half):
            wv = mp.fsum(w[k] * t**k for k in range(nterms + 2))
            Mv = mp.fsum(M[k] * t**k for k in range(nterms + 2))
            Qv = mp.fsum(k * M[k] * t**(k - 1) for k in range(1, nterms + 2))
            vals.append((wv, Mv, Qv))
        (wl, Ml, Ql), (wr, Mr, Qr) = vals
        cols.append([Ml, Ql, Mr, Qr + m_tip * w2 * wr])
    A = mp.matrix(4, 4)
    for j in range(4):
        for i in range(4):
            A[i, j] = cols[j][i]
    return mp.det(A)


def roots_series(m_tip, count, dps, nterms):
    with mp.workdps(dps):
        mt = mp.mpf(m_tip)
        f = lambda om: series_det(om, mt, nterms)
        return mp_roots.bracketed_roots(f, count, "0.5", "0.05")


# ---------------------------------------------------------------- method 2
def shoot_det(omega, m_tip):
    w2 = omega**2

    def rhs(x, y):
        return [y[1], y[2] / EI_of(x), y[3], m_of(x) * w2 * y[0]]

    ends = []
    for y0 in ([1.0, 0, 0, 0], [0, 1.0, 0, 0]):
        sol = solve_ivp(rhs, (0.0, L), y0, method="DOP853", rtol=1e-13, atol=1e-16)
        ends.append(sol.y[:, -1])
    a, b = ends
    r = lambda y: (y[2], y[3] + m_tip * w2 * y[0])
    ra, rb = r(a), r(b)
    return ra[0] * rb[1] - ra[1] * rb[0]


def roots_shoot(m_tip, guesses):
    out = []
    for g in guesses:
        lo, hi = g * (1 - 1e-6), g * (1 + 1e-6)
        out.append(brentq(shoot_det, lo, hi, args=(m_tip,), xtol=1e-14, rtol=1e-15))
    return out


# ---------------------------------------------------------------- method 3
def pfem(m_tip, p):
    pts = [(L, m_tip, 0.0)] if m_tip > 0 else []
    K, M = beam_pfem.assemble(np.linspace(0, L, 5), p, EI_of, m_of, points=pts)
    return np.sqrt(beam_pfem.eigenvalues(K, M, NMODES + 2)[2:])


def main():
    rows = []
    for name, m_tip in CASES.items():
        r60 = roots_series(m_tip, NMODES, 60, 260)
        r80 = roots_series(m_tip, NMODES, 80, 360)
        dev = max(abs(a / b - 1) for a, b in zip(r60, r80))
        print("%s: series roots at 60 digits/260 terms vs 80/360 differ by %s"
              % (name, mp.nstr(dev, 3)))
        ref = [float(r) for r in r80]
        shoot = roots_shoot(m_tip, ref)
        print("  p-FE convergence (relative to method 1):")
        for p in (8, 12, 16, 20, 24):
            w = pfem(m_tip, p)
            print("   p=%2d  " % p + " ".join("%.1e" % abs(w[i] / ref[i] - 1) for i in range(NMODES)))
        wp = pfem(m_tip, 24)
        for i in range(NMODES):
            rs = shoot[i] / ref[i] - 1
            rp = wp[i] / ref[i] - 1
            rows.append((name, i + 1, ref[i], shoot[i], rs, wp[i], rp))
            print("  mode %d omega = %s rad/s; shooting %.1e, p-FE %.1e"
                  % (i + 1, mp.nstr(r80[i], 20), rs, rp))
    with open(OUT, "w") as fh:
        fh.write("case,mode,omega_rad_s,omega_shoot_rad_s,rel_shoot,omega_pfem_rad_s,rel_pfem\n")
        for (name, mode, om, sh, rs, wp, rp) in rows:
            fh.write("%s,%d,%r,%r,%.2e,%r,%.2e\n" % (name, mode, om, float(sh), rs, float(wp), rp))
    print("wrote", os.path.normpath(OUT))


if __name__ == "__main__":
    main()
