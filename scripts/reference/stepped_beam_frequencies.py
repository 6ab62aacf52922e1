#!/usr/bin/python3
"""Reference A: elastic frequencies of free-free stepped beams (issue 15, acceptance 1).

Computes the first five elastic natural frequencies omega (rad/s) of three free-free
planar Euler-Bernoulli beams:
  stepped_bare     two segments from the left end: 0.6 m at 1.2 kg/m, EI 2 N m^2, then
                   0.4 m at 0.6 kg/m, EI 0.8 N m^2 (L = 1 m);
  stepped_hub_tip  the same beam with a rigid hub at s = 0.5 m (point body: mass 0.3 kg,
                   rotary inertia 0.002 kg m^2 about its centre) and a point mass 0.1 kg
                   at the right end s = 1.0 m (no rotary inertia);
  uniform          L = 1 m, 1 kg/m, EI 1 N m^2 (sanity check: omega = lambda^2
                   sqrt(EI/(m L^3)) with the classical lambda = 4.730040744862704, ...).

Method 1 (the reference, column omega_rad_s): transfer matrices. In a uniform piece the
state (w, w', M = EI w'', Q = (EI w'')') moves by the closed-form Krylov-function matrix
of EI w'''' = m omega^2 w; at a point body the state jumps by
    Q+ = Q- + mass omega^2 w,     M+ = M- - J omega^2 w'
(from Hamilton's principle: the body's inertia forces balance the jumps of shear and
moment). Free ends: M = Q = 0, so the 2x2 minor of the product matrix (rows M, Q; columns
w, w') is the characteristic function. Roots are bracketed by a sign scan and polished
with mpmath's Anderson root finder at 50 digits, then recomputed at 80 digits: the two
agree to < 1e-40, so the CSV value (rounded to a double, 17 significant digits) is
exact to the double's rounding, ~1e-16 relative.

Method 2 (cross-check, column omega_pfem_rad_s): p-version FE Rayleigh-Ritz (own code,
beam_pfem.py): element ends at the segment junction and the point bodies, each piece
halved (4 to 6 elements), polynomial degree p per element, exponential convergence.
The value at p = 24 is written; the convergence table p = 8..24 is printed. Agreement
with method 1: column rel_diff, measured <= 9e-16 except the hub case's mode 1, 5e-14
(round-off of the Rayleigh quotient; it is converged by p = 12).

Also the uniform case's lambda from method 1 is compared with the classical values
(cosh(l) cos(l) = 1) given above (agreement ~1e-16).

Run: python3 scripts/reference/stepped_beam_frequencies.py
Writes tests/reference/stepped_beam_frequencies.csv (columns: case, mode, omega_rad_s,
lambda, omega_pfem_rad_s, rel_diff). lambda = sqrt(omega) (m_ref L^4/EI_ref)^(1/4) with
m_ref, EI_ref of the first (left) segment, L = 1 m; for the uniform beam it is the
classical lambda.
Run time: 10-30 s.
"""
import os

import reexec  # noqa: F401  (first: may re-run this script with Debian's python3)
import numpy as np
import mpmath as mp

import beam_pfem  # the script's folder is on sys.path
import mp_roots

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "..", "tests", "reference", "stepped_beam_frequencies.csv")

# Beam descriptions: segments (length, m, EI) from the left; point bodies (s, mass, J).
CASES = {
    "stepped_bare": dict(segments=[(0.6, 1.2, 2.0), (0.4, 0.6, 0.8)], points=[]),
    "stepped_hub_tip": dict(segments=[(0.6, 1.2, 2.0), (0.4, 0.6, 0.8)],
                            points=[(0.5, 0.3, 0.002), (1.0, 0.1, 0.0)]),
    "uniform": dict(segments=[(1.0, 1.0, 1.0)], points=[]),
}
NMODES = 5
CLASSICAL_LAMBDA = [4.730040744862704, 7.853204624095838, 10.99560783800167,
                    14.13716549125746, 17.27875965739948]


# ---------------------------------------------------------------- method 1
def field_matrix(length, m, EI, omega):
    """Closed-form transfer matrix of a uniform piece for state (w, w', M, Q)."""
    beta = mp.sqrt(mp.sqrt(m * omega**2 / EI))
    z = beta * length
    ch, sh, c, s = mp.cosh(z), mp.sinh(z), mp.cos(z), mp.sin(z)
    S = (ch + c) / 2   # Krylov functions: S' = V, V' = U, U' = T, T' = S (in z)
    T = (sh + s) / 2
    U = (ch - c) / 2
    V = (sh - s) / 2
    b = beta
    return mp.matrix([
        [S, T / b, U / (EI * b**2), V / (EI * b**3)],
        [b * V, S, T / (EI * b), U / (EI * b**2)],
        [EI * b**2 * U, EI * b * V, S, T / b],
        [EI * b**3 * T, EI * b**2 * U, b * V, S],
    ])


def point_matrix(mass, J, omega):
    P = mp.eye(4)
    P[2, 1] = -J * omega**2      # M+ = M- - J omega^2 w'
    P[3, 0] = mass * omega**2    # Q+ = Q- + mass omega^2 w
    return P


def characteristic(case, omega):
    """det of the (M, Q) x (w, w') block of the left-to-right transfer matrix."""
    segs = case["segments"]
    pts = sorted(case["points"])
    # walk the beam, cutting segments at point bodies
    T = mp.eye(4)
    x = mp.mpf(0)
    pi = 0
    for (length, m, EI) in segs:
        x_end = x + mp.mpf(length)
        pos = x
        while pi < len(pts) and pts[pi][0] <= float(x_end) + 1e-12:
            s, mass, J = pts[pi]
            s = mp.mpf(s)
            if s > pos:
                T = field_matrix(s - pos, mp.mpf(m), mp.mpf(EI), omega) * T
                pos = s
            T = point_matrix(mp.mpf(mass), mp.mpf(J), omega) * T
            pi += 1
        if x_end > pos:
            T = field_matrix(x_end - pos, mp.mpf(m), mp.mpf(EI), omega) * T
        x = x_end
    return T[2, 0] * T[3, 1] - T[2, 1] * T[3, 0]


def roots_transfer(case, count, dps):
    with mp.workdps(dps):
        f = lambda om: characteristic(case, om)
        return mp_roots.bracketed_roots(f, count, "0.05", "0.01")


# ---------------------------------------------------------------- method 2
def pfem_omegas(case, p):
    segs = case["segments"]
    cuts = [0.0]
    for (length, _, _) in segs:
        cuts.append(cuts[-1] + length)
    nodes = sorted(set([round(c, 12) for c in cuts] +
                       [round(s, 12) for (s, _, _) in case["points"]]))
    # halve every element so each segment has at least two elements
    fine = []
    for a, b in zip(nodes[:-1], nodes[1:]):
        fine += [a, 0.5 * (a + b)]
    fine.append(nodes[-1])
    bounds = np.cumsum([0.0] + [sg[0] for sg in segs])

    def piece(x, k):
        idx = np.clip(np.searchsorted(bounds, x, side="right") - 1, 0, len(segs) - 1)
        return np.array([segs[i][k] for i in np.atleast_1d(idx)])

    EI = lambda x: piece(x, 2)
    m = lambda x: piece(x, 1)
    K, M = beam_pfem.assemble(fine, p, EI, m, points=case["points"])
    ev = beam_pfem.eigenvalues(K, M, NMODES + 2)
    return np.sqrt(ev[2:])   # skip the two rigid modes (omega = 0)


def main():
    rows = []
    for name, case in CASES.items():
        r50 = roots_transfer(case, NMODES, 50)
        r80 = roots_transfer(case, NMODES, 80)
        dev = max(abs(a / b - 1) for a, b in zip(r50, r80))
        print("%s: transfer-matrix roots at 50 vs 80 digits differ by %s (relative)"
              % (name, mp.nstr(dev, 3)))
        print("  p-FE convergence (relative to method 1):")
        for p in (8, 12, 16, 20, 24):
            w = pfem_omegas(case, p)
            err = [abs(float(w[i] / r80[i] - 1)) for i in range(NMODES)]
            print("   p=%2d  " % p + " ".join("%.1e" % e for e in err))
        w_pfem = pfem_omegas(case, 24)
        m0, EI0 = case["segments"][0][1], case["segments"][0][2]
        for i in range(NMODES):
            om = r80[i]
            lam = mp.sqrt(om) * (mp.mpf(m0) / EI0) ** mp.mpf("0.25")
            rel = float(w_pfem[i] / om - 1)
            rows.append((name, i + 1, om, lam, w_pfem[i], rel))
            print("  mode %d  omega = %s rad/s  lambda = %s  p-FE rel diff %.1e"
                  % (i + 1, mp.nstr(om, 20), mp.nstr(lam, 18), rel))
            if name == "uniform":
                print("     classical lambda %.15f, rel diff %.1e"
                      % (CLASSICAL_LAMBDA[i], float(lam / CLASSICAL_LAMBDA[i] - 1)))
    with open(OUT, "w") as fh:
        fh.write("case,mode,omega_rad_s,lambda,omega_pfem_rad_s,rel_diff\n")
        for (name, mode, om, lam, wp, rel) in rows:
            fh.write("%s,%d,%r,%r,%r,%.2e\n" % (name, mode, float(om), float(lam), float(wp), rel))
    print("wrote", os.path.normpath(OUT))


if __name__ == "__main__":
    main()
