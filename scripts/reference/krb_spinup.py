#!/usr/bin/python3
"""Reference D: the Kane-Ryan-Banerjee (1987) spin-up of a cantilever (issue 14, acceptance 1).

Problem. A uniform cantilever, L = 10 m, EI = 14 000 N m^2, rhoA = 1.2 kg/m,
EA = 2.8e7 N (E = 7e10 Pa, A = 4e-4 m^2), clamped at the axis of a hub of radius 0
whose angle is prescribed:
    theta(t) = (Os/Ts) [t^2/2 + (Ts/(2 pi))^2 (cos(2 pi t/Ts) - 1)]  for t < Ts = 15 s,
    theta'(t) = Os afterwards (angle and rate continuous), Os = 4 and 6 rad/s,
starting at rest, undeformed; 0 <= t <= 20 s; planar motion, no gravity.
Output: the tip's displacement in the frame turning with theta: v = transverse (the
tip's y in that frame; its rigid position is (L, 0)), u = axial (x - L).

Nonlinear model (the reference). Rotating frame, material point X in [0, L] at
(X + u, v). Kinetic energy (1/2) int rhoA |velocity|^2 with the inertial velocity
(u_t - theta' v, v_t + theta' (X + u)); hence the rotating-frame accelerations
    a_x = u_tt - 2 theta' v_t - theta'' v - theta'^2 (X + u)
    a_y = v_tt + 2 theta' u_t + theta'' (X + u) - theta'^2 v
(centrifugal, Coriolis and Euler terms all kept, no linearisation). Strain energy
(1/2) int (EA e^2 + EI kappa^2) with, selectable by --strain:
    exact  (default) e = |r'| - 1, kappa = ((1+u') v'' - v' u'') / |r'|^2, r' = (1+u', v'):
           the geometrically exact extensible, shear-rigid (Kirchhoff) planar rod;
    gl     e = u' + (u'^2 + v'^2)/2 (Green-Lagrange), kappa = v'';
    vk     e = u' + v'^2/2 (von Karman), kappa = v''.
Discretisation: n equal elements, Hermite cubics for both u and v (node DOFs u, u', v,
v'; clamped: u = v = v' = 0 at X = 0; u' free), 6-point Gauss quadrature per element,
consistent mass. The energy density's gradient and Hessian come from sympy, so the
internal force and the tangent stiffness are exact derivatives of the discrete energy.
Time: scipy's Radau IIA (order 5, L-stable) with the exact Jacobian, atol = 1e-2 rtol
(displacements) and rtol (velocities), in two pieces [0, Ts] and [Ts, 20] (the third
derivative of theta jumps at Ts); output every 0.01 s through Radau's dense output. The
CSV: n = 32, rtol = 1e-8, geometrically exact strain; a von Karman run (n = 16, rtol
1e-8) is written beside it. (At rtol 1e-10 scipy's Radau stalls on the Os = 6 run, so
1e-9 is the tightest tolerance used.)

Linear model WITHOUT stiffening (the model that fails): small transverse bending in the
rotating frame, no axial DOF, no axial force:
    rhoA (v_tt + theta'' X - theta'^2 v) + EI v'''' = 0,
solved by exact cantilever modes (the first 16), each modal equation
    eta_i'' + (w_i^2 - theta'^2) eta_i = -theta'' P_i,  P_i = int rhoA phi_i X dX,
integrated with DOP853 (rtol 1e-12). Output until 20 s or the last 0.01 s step before
|v_tip| passes 1000 m.

Accuracy (`--study`, ~15 min; its figures are tabulated in tests/reference/README.md):
element count n = 8, 16, 32 at rtol 1e-8; rtol 1e-6, 1e-8, 1e-9 at n = 16; best run
n = 32, rtol 1e-9. The CSV's v_tip is within ~1e-7 of the peak |v_tip| of the best run
(target 2e-3). The strain measures (exact, Green-Lagrange, von Karman) differ by 0.1-0.3 %
of the peak: a modelling choice, larger than the numerical error. The study also
linearises the model about steady spin (frequencies vs reference C) and checks the
linear model against a full Hermite FE solution.

Run: python3 scripts/reference/krb_spinup.py           (writes the CSVs; ~3 min)
     python3 scripts/reference/krb_spinup.py --study   (convergence study only)
Writes tests/reference/krb_spinup_nonlinear.csv (t_s, theta_os4_rad, theta_dot_os4_rad_s,
tip_v_os4_m, tip_u_os4_m, tip_v_os6_m, tip_u_os6_m, tip_v_vk_os4_m, tip_u_vk_os4_m,
tip_v_vk_os6_m, tip_u_vk_os6_m) and tests/reference/krb_spinup_linear_os4.csv,
krb_spinup_linear_os6.csv (t_s, tip_v_m).
"""
import os
import sys
import time

import reexec  # noqa: F401  (first: may re-run this script with Debian's python3)
import numpy as np
from beam_pfem import hermite_cubics as hermite
import scipy.linalg as sl
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
import sympy as sp

HERE = os.path.dirname(os.path.abspath(__file__))
OUTDIR = os.path.join(HERE, "..", "..", "tests", "reference")

L = 10.0
EI = 14000.0
RHOA = 1.2
EA = 2.8e7
TS = 15.0
T_END = 20.0
DT_OUT = 0.01


# ---------------------------------------------------------------- prescribed motion
def theta(t, Os):
    if t < TS:
        return Os / TS * (t * t / 2 + (TS / (2 * np.pi)) ** 2 * (np.cos(2 * np.pi * t / TS) - 1))
    return Os * TS / 2 + Os * (t - TS)      # theta(Ts) = Os Ts / 2


def theta_d(t, Os):
    if t < TS:
        return Os / TS * (t - TS / (2 * np.pi) * np.sin(2 * np.pi * t / TS))
    return Os


def theta_dd(t, Os):
    if t < TS:
        return Os / TS * (1 - np.cos(2 * np.pi * t / TS))
    return 0.0


# ---------------------------------------------------------------- energy density
def make_density(strain):
    a, b, c, d = sp.symbols("a b c d", real=True)   # u', v', u'', v''
    if strain == "exact":
        s2 = (1 + a) ** 2 + b ** 2
        e = sp.sqrt(s2) - 1
        kap = ((1 + a) * d - b * c) / s2
    elif strain == "gl":
        e = a + (a * a + b * b) / 2
        kap = d
    elif strain == "vk":
        e = a + b * b / 2
        kap = d
    else:
        raise ValueError("strain must be exact, gl or vk")
    W = sp.Rational(1, 2) * sp.Float(EA) * e ** 2 + sp.Rational(1, 2) * sp.Float(EI) * kap ** 2
    v = [a, b, c, d]
    grad = [sp.diff(W, x) for x in v]
    hess = [[sp.diff(g, x) for x in v] for g in grad]
    fg = sp.lambdify(v, grad, "numpy")
    fh = sp.lambdify(v, hess, "numpy")

    def grad_hess(loc):
        A, B, C, D = loc[..., 0], loc[..., 1], loc[..., 2], loc[..., 3]
        z = np.zeros_like(A)
        g = np.stack([np.asarray(x) + z for x in fg(A, B, C, D)], axis=-1)
        h = np.stack([np.stack([np.asarray(x) + z for x in row], axis=-1) for row in fh(A, B, C, D)], axis=-2)
        return g, h
    return grad_hess


# ---------------------------------------------------------------- finite elements


class RotatingBeam:
    """Planar beam in the frame of the hub; full DOF vector has 4 per node (u, u', v, v')."""

    def __init__(self, n, strain="exact", ngauss=6):
        self.n = n
        h = L / n
        xg, wg = np.polynomial.legendre.leggauss(ngauss)
        xi = (xg + 1) / 2
        wJ = wg * h / 2
        N, N1, N2 = hermite(xi, h)          # (4, ng)
        nfull = 4 * (n + 1)
        M = np.zeros((nfull, nfull))
        S = np.zeros((nfull, nfull))
        fu = np.zeros(nfull)
        fv = np.zeros(nfull)
        uidx = np.array([0, 1, 4, 5])
        vidx = np.array([2, 3, 6, 7])
        B = np.zeros((ngauss, 4, 8))        # rows: u', v', u'', v''; same for every element
        B[:, 0, uidx] = N1.T
        B[:, 1, vidx] = N1.T
        B[:, 2, uidx] = N2.T
        B[:, 3, vidx] = N2.T
        me = (N * (RHOA * wJ)) @ N.T
        for e in range(n):
            X = e * h + xi * h
            base = 4 * e
            iu = base + uidx
            iv = base + vidx
            M[np.ix_(iu, iu)] += me
            M[np.ix_(iv, iv)] += me
            S[np.ix_(iu, iv)] += me            # u rows: + C q_v
            S[np.ix_(iv, iu)] -= me            # v rows: - C^T q_u
            fx = N @ (RHOA * X * wJ)
            fu[iu] += fx
            fv[iv] += fx
        free = np.array([i for i in range(nfull) if i not in (0, 2, 3)])
        self.free = free
        self.nfull = nfull
        self.M = M[np.ix_(free, free)]
        self.S = S[np.ix_(free, free)]
        self.fu = fu[free]
        self.fv = fv[free]
        self.cho = sl.cho_factor(self.M)
        self.Minv = sl.cho_solve(self.cho, np.eye(len(free)))
        self.MinvS = self.Minv @ self.S
        self.Minv_fu = self.Minv @ self.fu
        self.Minv_fv = self.Minv @ self.fv
        self.B = B
        self.wJ = wJ
        self.gh = make_density(strain)
        self.elem_idx = 4 * np.arange(n)[:, None] + np.arange(8)[None, :]
        self.tip_u = list(free).index(4 * n)
        self.tip_v = list(free).index(4 * n + 2)

    def internal(self, q, tangent=False):
        qf = np.zeros(self.nfull)
        qf[self.free] = q
        de = qf[self.elem_idx]                              # (ne, 8)
        loc = np.einsum("gij,ej->egi", self.B, de)          # (ne, ng, 4)
        g, hmat = self.gh(loc)
        fe = np.einsum("g,gij,egi->ej", self.wJ, self.B, g)
        F = np.zeros(self.nfull)
        np.add.at(F, self.elem_idx, fe)
        F = F[self.free]
        if not tangent:
            return F
        ke = np.einsum("g,gia,egij,gjb->eab", self.wJ, self.B, hmat, self.B)
        K = np.zeros((self.nfull, self.nfull))
        for e in range(self.n):
            ix = self.elem_idx[e]
            K[np.ix_(ix, ix)] += ke[e]
        return F, K[np.ix_(self.free, self.free)]

    def rhs(self, t, y, Os):
        m = len(self.free)
        q, p = y[:m], y[m:]
        td, tdd = theta_d(t, Os), theta_dd(t, Os)
        F = self.internal(q)
        acc = (2 * td * (self.MinvS @ p) + tdd * (self.MinvS @ q) + td * td * q
               + td * td * self.Minv_fu - tdd * self.Minv_fv - sl.cho_solve(self.cho, F))
        return np.concatenate([p, acc])

    def jac(self, t, y, Os):
        m = len(self.free)
        q = y[:m]
        td, tdd = theta_d(t, Os), theta_dd(t, Os)
        _, K = self.internal(q, tangent=True)
        J = np.zeros((2 * m, 2 * m))
        J[:m, m:] = np.eye(m)
        J[m:, :m] = tdd * self.MinvS + td * td * np.eye(m) - self.Minv @ K
        J[m:, m:] = 2 * td * self.MinvS
        return J


def simulate(n, Os, strain="exact", rtol=1e-10, t_out=None):
    beam = RotatingBeam(n, strain)
    m = len(beam.free)
    atol = np.concatenate([np.full(m, rtol * 1e-2), np.full(m, rtol)])
    if t_out is None:
        t_out = np.round(np.arange(0, T_END + DT_OUT / 2, DT_OUT), 10)
    y = np.zeros(2 * m)
    out_t, out_y = [], []
    nfev = 0
    for (a, b) in ((0.0, TS), (TS, T_END)):
        te = t_out[(t_out >= a) & (t_out <= b)]
        if a > 0:
            te = te[te > a]
        sol = solve_ivp(beam.rhs, (a, b), y, method="Radau", t_eval=te, args=(Os,),
                        jac=beam.jac, rtol=rtol, atol=atol)
        if sol.status != 0:
            raise RuntimeError(sol.message)
        nfev += sol.nfev
        y = sol.y[:, -1]
        out_t.append(sol.t)
        out_y.append(sol.y)
    T = np.concatenate(out_t)
    Y = np.concatenate(out_y, axis=1)
    return T, Y[beam.tip_v], Y[beam.tip_u], nfev


# ---------------------------------------------------------------- linear model, exact modes
def cantilever_modes(count):
    """Roots of 1 + cos(b) cosh(b) = 0 and the mode-shape functions (unit modal mass)."""
    f = lambda b: 1 + np.cos(b) * np.cosh(b)
    betas = []
    for k in range(count):
        guess = (2 * k + 1) * np.pi / 2
        betas.append(brentq(f, guess - 1.0 + 1e-9 if k == 0 else guess - 0.5, guess + 0.5, xtol=1e-15))
    return np.array(betas)


def linear_simulate(Os, nmodes=12, stop=1000.0):
    betas = cantilever_modes(nmodes) / L            # beta_i (1/m)
    omega = betas**2 * np.sqrt(EI / RHOA)
    X, wq = np.polynomial.legendre.leggauss(200)
    X = (X + 1) * L / 2
    wq = wq * L / 2
    def shape(b, x):
        # cos - s sin - (cosh - s sinh), s = (cosh bL + cos bL)/(sinh bL + sin bL), with the
        # growing exponentials folded so that high modes do not cancel catastrophically
        bl = b * L
        num = -np.exp(-bl) + np.sin(bl) - np.cos(bl)
        den = 1 - np.exp(-2 * bl) + 2 * np.sin(bl) * np.exp(-bl)
        s = 1 - 2 * num * np.exp(-bl) / den
        ch = 0.5 * np.exp(-b * x) * (1 + s) + num * np.exp(b * x - bl) / den
        return np.cos(b * x) - s * np.sin(b * x) - ch

    P, tip = [], []
    for b in betas:
        phi = shape(b, X)
        mass = np.sum(RHOA * phi**2 * wq)
        phi = phi / np.sqrt(mass)
        P.append(np.sum(RHOA * phi * X * wq))
        tip.append(shape(b, L) / np.sqrt(mass))
    P, tip = np.array(P), np.array(tip)

    def rhs(t, y):
        eta, deta = y[:nmodes], y[nmodes:]
        td, tdd = theta_d(t, Os), theta_dd(t, Os)
        return np.concatenate([deta, -(omega**2 - td * td) * eta - tdd * P])

    def big(t, y):
        return abs(tip @ y[:nmodes]) - stop
    big.terminal = True

    t_out = np.round(np.arange(0, T_END + DT_OUT / 2, DT_OUT), 10)
    y = np.zeros(2 * nmodes)
    Ts_, Vs = [], []
    for (a, b) in ((0.0, TS), (TS, T_END)):
        te = t_out[(t_out >= a) & (t_out <= b)]
        if a > 0:
            te = te[te > a]
        sol = solve_ivp(rhs, (a, b), y, method="DOP853", t_eval=te, rtol=1e-12, atol=1e-14,
                        events=big)
        Ts_.append(sol.t)
        Vs.append(tip @ sol.y[:nmodes])
        y = sol.y[:, -1]
        if sol.status == 1:
            break
    return np.concatenate(Ts_), np.concatenate(Vs), omega


def linear_fe_simulate(n, Os, t_out):
    """Cross-check of the linear model: Hermite FE (v only, from RotatingBeam), DOP853."""
    b = RotatingBeam(n, "vk")
    vfree = np.array([i for i, g in enumerate(b.free) if g % 4 in (2, 3)])
    _, K0 = b.internal(np.zeros(len(b.free)), tangent=True)
    M = b.M[np.ix_(vfree, vfree)]
    K = K0[np.ix_(vfree, vfree)]
    fv = b.fv[vfree]
    Minv = np.linalg.inv(M)
    MK = Minv @ K
    Mf = Minv @ fv
    m = len(vfree)
    tip = list(vfree).index(b.tip_v)

    def rhs(t, y):
        td, tdd = theta_d(t, Os), theta_dd(t, Os)
        return np.concatenate([y[m:], td * td * y[:m] - MK @ y[:m] - tdd * Mf])

    y = np.zeros(2 * m)
    out = []
    for (a, c) in ((0.0, TS), (TS, t_out[-1])):
        te = t_out[(t_out >= a) & (t_out <= c)]
        if a > 0:
            te = te[te > a]
        if len(te) == 0:
            continue
        # the FE system in full (no modal truncation); DOP853's step is bound by the mesh's
        # highest frequency, so keep n small (Radau stalled here on the growing solution)
        sol = solve_ivp(rhs, (a, min(c, t_out[-1])), y, method="DOP853", t_eval=te,
                        rtol=1e-10, atol=1e-12)
        out.append(sol.y[tip])
        y = sol.y[:, -1]
    return np.concatenate(out)


def write_csv(path, header, cols, fmt):
    with open(path, "w") as fh:
        fh.write(header + "\n")
        for row in zip(*cols):
            fh.write(",".join(f % v for f, v in zip(fmt, row)) + "\n")
    print("wrote", os.path.normpath(path))


def spin_frequency_check():
    """Linearise the nonlinear FE model about steady spin and compare with reference C.

    The static equilibrium under spin (u only) is found by Newton; the small motions about
    it obey M q'' - 2 Omega S q' + (K_T - Omega^2 M) q = 0 (centrifugal softening, Coriolis
    coupling to the axial DOFs). Its lowest in-plane frequencies must approach those of
    the inextensible rotating cantilever (rotating_cantilever_frequencies.py) up to the
    effect of axial extensibility and axial Coriolis coupling, O((2 Omega/w_axial)^2).
    """
    sys.path.insert(0, HERE)
    import rotating_cantilever_frequencies as rc
    scale = np.sqrt(EI / (RHOA * L**4))
    for Os in (4.0, 6.0):
        gamma = Os / scale
        ref = np.array([float(r) * scale for r in rc.roots_series(gamma, 1, 3, 40, 200)])
        for n in (16, 32):
            b = RotatingBeam(n, "exact")
            m = len(b.free)
            q = np.zeros(m)
            for _ in range(30):
                F, K = b.internal(q, True)
                dq = np.linalg.solve(K - Os**2 * b.M, -(F - Os**2 * (b.M @ q + b.fu)))
                q += dq
                if np.linalg.norm(dq) < 1e-15:
                    break
            F, K = b.internal(q, True)
            A = np.zeros((2 * m, 2 * m))
            A[:m, m:] = np.eye(m)
            A[m:, :m] = b.Minv @ (Os**2 * b.M - K)
            A[m:, m:] = 2 * Os * b.MinvS
            ev = np.linalg.eigvals(A)
            w = np.sort(np.abs(ev.imag[ev.imag > 0]))[:3]
            print("Os=%g (gamma %.6f) n=%d: static tip u %.7e m (small-strain rhoA Os^2 L^3/(3 EA) = "
                  "%.7e); omegas %s rad/s vs reference C %s: rel %s"
                  % (Os, gamma, n, q[b.tip_u], RHOA * Os**2 * L**3 / (3 * EA), np.array2string(w, precision=8),
                     np.array2string(ref, precision=8), np.array2string(w / ref - 1, precision=2)))


def study():
    spin_frequency_check()
    for Os in (4.0, 6.0):
        Tl, vl, _ = linear_simulate(Os, 16)
        Tl12, vl12, _ = linear_simulate(Os, 12)
        for n in (8, 16):
            vf = linear_fe_simulate(n, Os, Tl)
            print("linear model Os=%g: 16 exact modes vs Hermite FE n=%d (DOP853 1e-10): max |diff| / max |v| "
                  "= %.2e over 0..%.2f s; vs 12 modes %.2e" % (Os, n, np.max(np.abs(vf - vl)) / np.max(np.abs(vl)),
                                                             Tl[-1], np.max(np.abs(vl12 - vl)) / np.max(np.abs(vl))),
                  flush=True)
    for Os in (4.0, 6.0):
        runs = {}
        for (n, rtol, strain) in [(8, 1e-8, "exact"), (16, 1e-8, "exact"), (32, 1e-8, "exact"),
                                  (16, 1e-6, "exact"), (16, 1e-9, "exact"), (32, 1e-9, "exact"),
                                  (16, 1e-8, "gl"), (16, 1e-8, "vk")]:
            t0 = time.time()
            T, v, u, nfev = simulate(n, Os, strain, rtol)
            runs[(n, rtol, strain)] = (v, u)
            print("Os=%g n=%2d rtol=%.0e %-5s: min v %.6f at %.2f s, max v %.6f, v(20) %.6f, "
                  "min u %.6f; nfev %d, %.0f s" % (Os, n, rtol, strain, v.min(), T[v.argmin()],
                                                   v.max(), v[-1], u.min(), nfev, time.time() - t0),
                  flush=True)
        best = runs[(32, 1e-9, "exact")][0]
        peak = np.max(np.abs(best))
        for k, (v, u) in runs.items():
            print("  Os=%g %s: max |v - v(32, 1e-9, exact)| / peak = %.2e"
                  % (Os, k, np.max(np.abs(v - best)) / peak))


def main():
    if "--study" in sys.argv:
        study()
        return
    t_start = time.time()
    res = {}
    for Os in (4.0, 6.0):
        T, v, u, nfev = simulate(32, Os, "exact", 1e-8)
        _, v_vk, u_vk, _ = simulate(16, Os, "vk", 1e-8)
        res[Os] = (T, v, u, v_vk, u_vk)
        print("Os = %g: tip v min %.6f m at t = %.2f s, max %.6f m; tip u min %.6f m (nfev %d); "
              "von Karman: v min %.6f m, max |v_vk - v| %.2e m"
              % (Os, v.min(), T[v.argmin()], v.max(), u.min(), nfev, v_vk.min(), np.max(np.abs(v_vk - v))),
              flush=True)
    T = res[4.0][0]
    write_csv(os.path.join(OUTDIR, "krb_spinup_nonlinear.csv"),
              "t_s,theta_os4_rad,theta_dot_os4_rad_s,tip_v_os4_m,tip_u_os4_m,tip_v_os6_m,tip_u_os6_m,"
              "tip_v_vk_os4_m,tip_u_vk_os4_m,tip_v_vk_os6_m,tip_u_vk_os6_m",
              [T, [theta(t, 4.0) for t in T], [theta_d(t, 4.0) for t in T], res[4.0][1], res[4.0][2],
               res[6.0][1], res[6.0][2], res[4.0][3], res[4.0][4], res[6.0][3], res[6.0][4]],
              ["%.2f", "%.12g", "%.12g"] + ["%.9e"] * 8)
    for Os in (4.0, 6.0):
        Tl, vl, omega = linear_simulate(Os, 16)
        print("linear Os = %g: first cantilever frequency %.6f rad/s; last t %.2f s, tip %.4g m"
              % (Os, omega[0], Tl[-1], vl[-1]))
        write_csv(os.path.join(OUTDIR, "krb_spinup_linear_os%d.csv" % int(Os)), "t_s,tip_v_m",
                  [Tl, vl], ["%.2f", "%.9e"])
    print("run time %.0f s" % (time.time() - t_start))


if __name__ == "__main__":
    main()
