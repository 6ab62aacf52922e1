#!/usr/bin/python3
"""Reference F: a free-free beam spun up by two follower tip thrusters (planar ANCF).

Problem. A uniform Euler-Bernoulli beam, L = 1 m, rhoA = 1 kg/m, EI = 1 N m^2, free-free,
planar, no gravity, at rest and straight at t = 0 with material point s in [0, 1] at
(s - 0.5, 0). Two follower thrusters: at s = 1 a force F(t) along n(1), at s = 0 a force
F(t) along -n(0), where n(s) is the unit tangent r'(s)/|r'(s)| turned by +90 deg; together
a couple of about F L turning the beam counter-clockwise. F = 0.5 N for 0 <= t < 2 s,
then 0 until 4 s. Outputs every 0.01 s:
    theta_o          angle of the unit tangent at s = 0.5 (unwrapped, from 0);
    Rx, Ry           position of s = 0.5;
    w_right, w_left  n_o . (r(1) - r(0.5)), n_o . (r(0) - r(0.5)), n_o the unit normal at
                     s = 0.5 (tangent turned +90 deg).
(For freeflex's paper basis these are theta, Rx, Ry, tip_right_m, tip_left_m of
nonlinear.csv: the body frame is the tangent at o = the mass centre s = 0.5.)

Model. The planar Absolute Nodal Coordinate Formulation (Shabana): Hermite cubic elements
whose nodal coordinates are the global position r and slope r' = dr/ds at each node (4 per
node), r(s) = S(s) e, no rotation or body frame anywhere. The mass matrix is constant
(consistent, exact), there are no velocity-dependent inertia terms. Strain energy
    U = int (EA/2 eps^2 + EI/2 kappa^2) ds,  eps = |r'| - 1,
    kappa = (r'_x r''_y - r'_y r''_x) / |r'|^3
(geometrically exact, extensible, shear-rigid), 6-point Gauss quadrature per element; the
energy density's gradient and Hessian come from sympy, so the internal force and tangent
stiffness are the exact derivatives of the discrete energy. The thrusters act on the end
nodes' positions (S(0), S(1) select them) with the direction taken from the end nodes'
slope coordinates (follower forces, with their exact Jacobian). freeflex's beam is
inextensible: the axial stiffness EA is a penalty, and the extensible result differs from
the inextensible one by O(1/EA): the centrifugal tension (~18 N at the centre at 12 rad/s)
stretches the beam, raises its inertia and slows the spin (theta_o(4 s) is 0.078 rad
lower at EA = 1e4 than in the limit). The CSV is the four-level Richardson extrapolation
in 1/EA of runs at EA_LADDER = 1e4, 2e4, 4e4, 8e4 N (removes the 1/EA .. 1/EA^3 terms):
    y = (64 y(8e4) - 56 y(4e4) + 14 y(2e4) - y(1e4)) / 21.
(Large EA directly is out of reach in CPU time: scipy's Radau with the exact Jacobian took
1.5e6 evaluations (280 s) at n = 8, EA = 1e6, and an explicit method's step falls as
1/sqrt(EA) once the axial modes bind it; a fixed-step Radau IIA at 0.0025 s damped the
step-excited high modes and missed theta_o by 3e-4 rad.)

Time: scipy's DOP853 (explicit Runge-Kutta, order 8), rtol = 1e-9, atol = 1e-2 rtol on
positions and slopes and rtol on their rates, in two pieces [0, 2] and [2, 4] (the thrust
steps off at 2 s: restarted there), output through the dense output. Two quadratures
ride along: the integral of the thrusters' moment about the mass centre and their work, so
that the angular momentum about the mass centre H_c(t) minus the integrated moment, and the
energy T + U minus the work, are conserved to integration error (printed: ~1e-14 N m s and
~1e-10 J).

Accuracy (measured 2026-11-27 from the runs `--study` makes, run one by one; max over
0-4 s of |theta_o| / |w_right| differences):
  rtol 1e-8 vs 1e-9 (n 16, EA 1e4): 9e-9 rad / 5e-9 m: time integration is not a factor;
  EA: 3-level (2e4, 4e4, 8e4) vs the 4-level extrapolation: 1.8e-4 rad / 9.6e-5 m
      (0-2 s: 2.6e-5 / 1.3e-5); 3-level (1e4 .. 4e4): 1.4e-3 / 7.7e-4, so the 4-level
      value is taken as good to ~1e-4 rad / 5e-5 m;
  mesh: n 8 vs n 16 (both extrapolated): 5.5e-3 rad / 2.5e-3 m (0-2 s: 2.2e-3 / 9.8e-4);
      n 16 vs n 32 at EA 1e4: 1.1e-3 rad / 6.0e-4 m (0-2 s: 7.0e-4 / 3.5e-4; 0.1 s
      moving averages: 1.9e-4 / 9.7e-5); n 8 vs 32: 4.7e-3 / 2.2e-3. So the CSV (n 16)
      is good to ~1e-3 rad / 6e-4 m only: the mesh is the dominant error. It is
      the phase of the step-excited antisymmetric modes at 417 rad/s and above (aliased
      to ~210 rad/s by the 0.01 s sampling), whose frequencies the mesh gets with h^4
      error but whose phase accumulates over 4 s.
  Checks: |H_c - int moment| < 1.1e-14 N m s, |E - work| < 6e-11 J in every run;
  Rx, Ry stay < 1e-14 m (the motion is antisymmetric about s = 0.5).

Run: python3 scripts/reference/free_spinup.py           (writes the CSV; 480 s wall, 2 cores)
     python3 scripts/reference/free_spinup.py --study   (convergence study only)
Writes tests/reference/free_spinup.csv (t, theta_o, Rx, Ry, w_right, w_left; SI units;
n = 16, rtol 1e-9, EA extrapolated from 1e4, 2e4, 4e4, 8e4).
"""
import os
import sys
import time

import reexec  # noqa: F401  (first: may re-run this script with Debian's python3)
import numpy as np
from beam_pfem import hermite_cubics as hermite
from scipy.integrate import solve_ivp
import sympy as sp

HERE = os.path.dirname(os.path.abspath(__file__))
OUTDIR = os.path.join(HERE, "..", "..", "tests", "reference")

L = 1.0
RHOA = 1.0
EI = 1.0
F_THRUST = 0.5
T_OFF = 2.0
T_END = 4.0
DT_OUT = 0.01

# settings of the CSV (justified by --study)
N_ELEM = 16
RTOL = 1e-9
EA_LADDER = (1e4, 2e4, 4e4, 8e4)


# ---------------------------------------------------------------- energy density
def make_density(EA):
    a, b, c, d = sp.symbols("a b c d", real=True)   # r'_x, r'_y, r''_x, r''_y
    s2 = a * a + b * b
    eps = sp.sqrt(s2) - 1
    kap = (a * d - b * c) / s2 ** sp.Rational(3, 2)
    W = sp.Rational(1, 2) * sp.Float(EA) * eps ** 2 + sp.Rational(1, 2) * sp.Float(EI) * kap ** 2
    v = [a, b, c, d]
    grad = [sp.diff(W, x) for x in v]
    hess = [[sp.diff(g, x) for x in v] for g in grad]
    fW = sp.lambdify(v, W, "numpy")
    fg = sp.lambdify(v, grad, "numpy")
    fh = sp.lambdify(v, hess, "numpy")

    def grad_hess(loc, want_hess=True):
        A, B, C, D = loc[..., 0], loc[..., 1], loc[..., 2], loc[..., 3]
        z = np.zeros_like(A)
        g = np.stack([np.asarray(x) + z for x in fg(A, B, C, D)], axis=-1)
        if not want_hess:
            return g
        h = np.stack([np.stack([np.asarray(x) + z for x in row], axis=-1)
                      for row in fh(A, B, C, D)], axis=-2)
        return g, h

    def energy(loc):
        return np.asarray(fW(loc[..., 0], loc[..., 1], loc[..., 2], loc[..., 3])) + 0 * loc[..., 0]
    return grad_hess, energy


# ---------------------------------------------------------------- ANCF beam
class AncfBeam:
    """Node i has coordinates e[4i:4i+4] = (r_x, r_y, r'_x, r'_y) at s_i = i L / n."""

    def __init__(self, n, EA, ngauss=6):
        assert n % 2 == 0, "n even: a node at s = 0.5"
        self.n = n
        h = L / n
        xg, wg = np.polynomial.legendre.leggauss(ngauss)
        xi = (xg + 1) / 2
        self.wJ = wg * h / 2
        N, N1, N2 = hermite(xi, h)                       # (4, ng)
        self.ndof = 4 * (n + 1)
        xi_ = np.array([0, 2, 4, 6])                     # element DOFs of x (r_x, r'_x at both nodes)
        yi_ = xi_ + 1
        B = np.zeros((ngauss, 4, 8))
        B[:, 0, xi_] = N1.T
        B[:, 1, yi_] = N1.T
        B[:, 2, xi_] = N2.T
        B[:, 3, yi_] = N2.T
        self.B = B
        me = (N * (RHOA * self.wJ)) @ N.T                # scalar consistent mass, (4, 4)
        mcol = N @ (RHOA * self.wJ)                      # int rhoA S ds per element
        self.elem_idx = 4 * np.arange(n)[:, None] + np.arange(8)[None, :]
        M = np.zeros((self.ndof, self.ndof))
        Ms = np.zeros((self.ndof, self.ndof))            # scalar part, x-x block only
        cm = np.zeros(self.ndof)                         # int rhoA r_x ds = cm . e
        for e in range(n):
            ix = self.elem_idx[e][xi_]
            iy = self.elem_idx[e][yi_]
            M[np.ix_(ix, ix)] += me
            M[np.ix_(iy, iy)] += me
            Ms[np.ix_(ix, ix)] += me
            cm[ix] += mcol
        self.M = M
        self.Minv = np.linalg.inv(M)
        self.mass = RHOA * L
        self.ix = np.arange(0, self.ndof, 4).tolist() + np.arange(2, self.ndof, 4).tolist()
        self.ix = np.sort(np.array(self.ix))             # all x-type DOFs
        self.iy = self.ix + 1
        self.Mss = Ms[np.ix_(self.ix, self.ix)]          # scalar mass on x (= on y) DOFs
        self.cms = cm[self.ix]
        self.gh, self.W = make_density(EA)
        # flat index pairs for assembling element stiffness matrices
        ii = np.repeat(self.elem_idx[:, :, None], 8, axis=2)
        jj = np.repeat(self.elem_idx[:, None, :], 8, axis=1)
        self.flat = (ii * self.ndof + jj).ravel()
        self.mid = 4 * (n // 2)

    def initial(self):
        e = np.zeros(self.ndof)
        s = np.linspace(0, L, self.n + 1)
        e[0::4] = s - 0.5 * L
        e[2::4] = 1.0
        return e

    def local(self, e):
        return np.einsum("gij,ej->egi", self.B, e[self.elem_idx])   # (ne, ng, 4)

    def internal(self, e, tangent=False):
        loc = self.local(e)
        if not tangent:
            g = self.gh(loc, False)
        else:
            g, hm = self.gh(loc)
        fe = np.einsum("g,gij,egi->ej", self.wJ, self.B, g)
        Fi = np.zeros(self.ndof)
        np.add.at(Fi, self.elem_idx, fe)
        if not tangent:
            return Fi
        ke = np.einsum("g,gia,egij,gjb->eab", self.wJ, self.B, hm, self.B)
        K = np.bincount(self.flat, weights=ke.ravel(), minlength=self.ndof**2)
        return Fi, K.reshape(self.ndof, self.ndof)

    def strain_energy(self, e):
        return np.einsum("g,eg->", self.wJ, self.W(self.local(e)))

    def thrust(self, e, F, jac=False):
        """Generalized thruster forces (and d/de). Right end: +F n(1) on node n's position,
        left end: -F n(0) on node 0's position; n = (-r'_y, r'_x)/|r'|."""
        Q = np.zeros(self.ndof)
        dQ = np.zeros((self.ndof, self.ndof)) if jac else None
        forces = []
        for node, sign in ((self.n, 1.0), (0, -1.0)):
            k = 4 * node
            a, b = e[k + 2], e[k + 3]
            rho = np.hypot(a, b)
            f = sign * F * np.array([-b, a]) / rho
            Q[k:k + 2] += f
            forces.append((e[k:k + 2].copy(), f))
            if jac:
                r3 = sign * F / rho**3
                dQ[k, k + 2] += r3 * a * b
                dQ[k, k + 3] += -r3 * a * a
                dQ[k + 1, k + 2] += r3 * b * b
                dQ[k + 1, k + 3] += -r3 * a * b
        return Q, dQ, forces

    def centre(self, e):
        return np.array([self.cms @ e[self.ix], self.cms @ e[self.iy]]) / self.mass

    def rhs(self, t, y, F):
        m = self.ndof
        e, v = y[:m], y[m:2 * m]
        Q, _, forces = self.thrust(e, F)
        acc = self.Minv @ (Q - self.internal(e))
        rc = self.centre(e)
        mom = sum((r[0] - rc[0]) * f[1] - (r[1] - rc[1]) * f[0] for r, f in forces)
        # power of the follower forces: f . velocity of the material point they act on
        pw = sum(f @ v[4 * node:4 * node + 2] for (r, f), node in zip(forces, (self.n, 0)))
        return np.concatenate([v, acc, [mom, pw]])

    def jac(self, t, y, F):
        m = self.ndof
        e = y[:m]
        _, K = self.internal(e, tangent=True)
        _, dQ, _ = self.thrust(e, F, jac=True)
        J = np.zeros((2 * m + 2, 2 * m + 2))
        J[:m, m:2 * m] = np.eye(m)
        J[m:2 * m, :m] = self.Minv @ (dQ - K)
        return J                                         # quadrature rows: left 0 (no feedback)

    def outputs(self, Y):
        """theta_o, Rx, Ry, w_right, w_left, H_c - int moment, E - work, from states (cols)."""
        m = self.ndof
        k = self.mid
        R = Y[k:k + 2]
        tx, ty = Y[k + 2], Y[k + 3]
        th = np.unwrap(np.arctan2(ty, tx))
        nrm = np.hypot(tx, ty)
        nx, ny = -ty / nrm, tx / nrm
        rr = Y[4 * self.n:4 * self.n + 2] - R
        rl = Y[0:2] - R
        wr = nx * rr[0] + ny * rr[1]
        wl = nx * rl[0] + ny * rl[1]
        H, E = [], []
        for col in Y.T:
            e, v = col[:m], col[m:2 * m]
            ex, ey, vx, vy = e[self.ix], e[self.iy], v[self.ix], v[self.iy]
            h = ex @ self.Mss @ vy - ey @ self.Mss @ vx
            rc, vc = self.centre(e), self.centre(v)
            h -= self.mass * (rc[0] * vc[1] - rc[1] * vc[0])
            H.append(h)
            E.append(0.5 * v @ self.M @ v + self.strain_energy(e))
        H = np.array(H)
        E = np.array(E)
        return dict(theta_o=th, Rx=R[0], Ry=R[1], w_right=wr, w_left=wl, H=H,
                    H_err=H - Y[2 * m], E=E, E_err=E - Y[2 * m + 1])


def simulate(n, EA, rtol=RTOL, method="DOP853", t_out=None):
    """Adaptive scipy integration (DOP853: explicit, order 8; its step is bound by the
    mesh's highest axial and bending frequencies, so EA is kept moderate), restarted at
    T_OFF, output through the dense output."""
    beam = AncfBeam(n, EA)
    m = beam.ndof
    if t_out is None:
        t_out = np.round(np.arange(0, T_END + DT_OUT / 2, DT_OUT), 10)
    atol = np.concatenate([np.full(m, 1e-2 * rtol), np.full(m, rtol), [rtol, rtol]])
    y = np.concatenate([beam.initial(), np.zeros(m + 2)])
    Ts, Ys, nfev = [], [], 0
    for (a, b, F) in ((0.0, T_OFF, F_THRUST), (T_OFF, T_END, 0.0)):
        te = t_out[(t_out >= a) & (t_out <= b)]
        if a > 0:
            te = te[te > a]
        kw = dict(jac=beam.jac) if method in ("Radau", "BDF") else {}
        sol = solve_ivp(beam.rhs, (a, b), y, method=method, t_eval=te, args=(F,),
                        rtol=rtol, atol=atol, **kw)
        if sol.status != 0:
            raise RuntimeError(sol.message)
        nfev += sol.nfev
        y = sol.y[:, -1]
        Ts.append(sol.t)
        Ys.append(sol.y)
    out = beam.outputs(np.concatenate(Ys, axis=1))
    out["t"] = np.concatenate(Ts)
    out["nfev"] = nfev
    return out


KEYS = ("theta_o", "Rx", "Ry", "w_right", "w_left")


def _run(args):
    n, EA, rtol = args
    t0 = time.time()
    r = simulate(n, EA, rtol)
    r["wall"] = time.time() - t0
    print("  n = %d, EA = %.0e, rtol %.0e: theta_o(4) = %.10f rad, max |H_c - int moment| "
          "%.1e N m s, max |E - work| %.1e J, %d evaluations, %.0f s"
          % (n, EA, rtol, r["theta_o"][-1], np.max(np.abs(r["H_err"])),
             np.max(np.abs(r["E_err"])), r["nfev"], r["wall"]), flush=True)
    return r


def run_all(cases):
    """The runs, two at a time (the machine has 2 cores)."""
    import multiprocessing as mp
    with mp.Pool(min(2, len(cases))) as pool:
        return dict(zip(cases, pool.map(_run, cases)))


def richardson_weights(EAs):
    """Weights w with sum w_i y(EA_i) exact for y polynomial in 1/EA of degree len(EAs)-1,
    evaluated at 1/EA = 0 (4 levels 1e4 .. 8e4: (-1, 14, -56, 64) / 21)."""
    x = EAs[0] / np.asarray(EAs, float)
    V = np.vander(x, increasing=True).T                 # rows: powers 0..m-1
    rhs = np.zeros(len(x))
    rhs[0] = 1.0
    return np.linalg.solve(V, rhs)


def richardson(runs, EAs):
    w = richardson_weights(EAs)
    out = {k: sum(wi * r[k] for wi, r in zip(w, runs)) for k in KEYS}
    out["t"] = runs[0]["t"]
    return out


def write_csv(path, header, cols, fmt):
    with open(path, "w") as fh:
        fh.write(header + "\n")
        for row in zip(*cols):
            fh.write(",".join(f % v for f, v in zip(fmt, row)) + "\n")
    print("wrote", os.path.normpath(path))


def maxdiff(a, b, upto=None):
    t = a["t"]
    sel = np.ones_like(t, bool) if upto is None else (t <= upto + 1e-9)
    return {k: np.max(np.abs(a[k][sel] - b[k][sel])) for k in ("theta_o", "w_right", "w_left")}


def fmt_d(d):
    return "theta %.2e rad, w_right %.2e m, w_left %.2e m" % (d["theta_o"], d["w_right"], d["w_left"])


def study():
    """Convergence: rtol (n 16, EA 1e4), EA (n 8, 16: Richardson with 2, 3, 4 levels) and
    element count (n 8, 16, 32 at EA 1e4; the EA-extrapolated n = 8 against n = 16).
    About 25 min on 2 cores."""
    t0 = time.time()
    lad = EA_LADDER
    cases = ([(16, EA, 1e-9) for EA in lad] + [(8, EA, 1e-9) for EA in lad]
             + [(16, 1e4, 1e-8), (16, 1e4, 1e-10), (32, 1e4, 1e-9)])
    res = run_all(cases)
    print("-- time tolerance (n = 16, EA = 1e4), against rtol 1e-10")
    for rt in (1e-8, 1e-9):
        print("rtol %.0e: %s" % (rt, fmt_d(maxdiff(res[(16, 1e4, rt)], res[(16, 1e4, 1e-10)]))))
    print("-- axial stiffness: extrapolations to 1/EA = 0 against the 4-level one")
    best = {}
    for n in (8, 16):
        x4 = richardson([res[(n, EA, 1e-9)] for EA in lad], lad)
        best[n] = x4
        for sub in (lad[:1], lad[3:], lad[2:], lad[:3], lad[1:]):
            x = richardson([res[(n, EA, 1e-9)] for EA in sub], sub)
            print("n %2d, EA %s: 0-4 s %s; 0-2 s %s" % (n, sub, fmt_d(maxdiff(x, x4)),
                                                      fmt_d(maxdiff(x, x4, 2.0))))
    print("-- element count (EA 1e4, rtol 1e-9), against n = 32")
    for n in (8, 16):
        print("n %d: 0-4 s %s; 0-2 s %s" % (n, fmt_d(maxdiff(res[(n, 1e4, 1e-9)], res[(32, 1e4, 1e-9)])),
                                           fmt_d(maxdiff(res[(n, 1e4, 1e-9)], res[(32, 1e4, 1e-9)], 2.0))))
    print("extrapolated n 8 vs n 16: %s" % fmt_d(maxdiff(best[8], best[16])))
    print("study: %.0f s" % (time.time() - t0))


def main():
    if "--study" in sys.argv:
        study()
        return
    t0 = time.time()
    cases = [(N_ELEM, EA, RTOL) for EA in EA_LADDER]
    res = run_all(cases)
    r = richardson([res[c] for c in cases], EA_LADDER)
    os.makedirs(OUTDIR, exist_ok=True)
    write_csv(os.path.join(OUTDIR, "free_spinup.csv"), "t,theta_o,Rx,Ry,w_right,w_left",
              [r["t"]] + [r[k] for k in KEYS], ["%.2f"] + ["%.17g"] * 5)
    print("free_spinup: n = %d, rtol %.0e, EA %s extrapolated; theta_o(4) = %.10f rad; %.0f s"
          % (N_ELEM, RTOL, EA_LADDER, r["theta_o"][-1], time.time() - t0))


if __name__ == "__main__":
    main()
