#!/usr/bin/python3
"""SciPy rows of the work-precision table (issue 19, acceptance 1 and 2).

The full nonlinear model of freeflex (docs/theory.md, eq. 6.2) written again here from
its kinetic energy, with the modal integrals freeflex exports (bench_accuracy --export):
z = [Rx, Ry, theta, q], T = z'^T M(theta, q) z' / 2, V = q^T K q / 2 with

    M_RR = m I,  M_Rtheta = C J s,  M_Rq = C e2 Phi_bar,  s = (S_o, Phi_bar q),
    M_thetatheta = I_o + q^T M q,  M_thetaq = Phi_tilde,  M_qq = M,

C the rotation by theta and J the quarter turn. Lagrange's equations
    M z'' = G - (dM/dt) z' + dT/dz - K q,
dM/dt and dT/dz written out from the derivatives of M (which depend on theta through C,
on q through s and q^T M q). The torque M_z at x = 0.5 m has G = u (0, 0, 1, Phi'(0.5)).

Check: this right-hand side against freeflex's FullModel::rhs at 20 random states (the
CSV from --export): the largest difference relative to the largest |x'| must be round-off,
below 1e-11 (measured: 1.1e-14 at NOA 6, 2.8e-13 at NOA 20, where the mass matrix's
condition number is larger), else the script stops.

Runs: the paper's moment pulse (+1 N m on [0, 0.5), -1 N m on [0.5, 1)), NOA 6 over
[0, 3] s and NOA 20 over [0, 1] s, integrated piece by piece ([0, 0.5], [0.5, 1], [1, T],
the load is smooth inside each) with solve_ivp's DOP853 and Radau (finite-difference
Jacobian) at rtol 1e-6 ... 1e-12, atol = rtol / 100, output every 10 ms. Error: max over
the output times of |theta - theta_ref| and |q - q_ref| against freeflex at rtol 1e-13
(the exported reference); the row "DOP853 1e-13" shows how far SciPy's tightest run is
from that reference. CPU time: time.process_time(), the minimum of the repetitions.

Radau runs at rtol 1e-6 and 1e-8 (NOA 6) and 1e-6 (NOA 20) only: with difference-quotient
Jacobians in Python it takes minutes beyond. `--noa=6`, `--noa=20` or `--noa=40` runs one
case (NOA 40 over [0, 1] s, as 20); `--rtols=1e-9,3e-10` runs DOP853 at those tolerances
only, no Radau (the rows around an error of 1e-4 rad for work at equal error).

Run: mkdir -p /tmp/ffx && build/bench/bench_accuracy --export /tmp/ffx && /usr/bin/python3 scripts/dop853_compare.py /tmp/ffx
"""
import json
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp


class FullModel:
    def __init__(self, data):
        self.n = n = data["noa"]
        self.N = n + 3
        self.m = data["m"]
        self.S_o = data["S_o"]
        self.I_o = data["I_o"]
        self.Pb = np.array(data["Phi_bar"])
        self.Pt = np.array(data["Phi_tilde"])
        self.M = np.array(data["M"])
        self.K = np.array(data["K"])
        self.g_torque = np.concatenate(([0.0, 0.0, 1.0], np.array(data["torque_slope"])))

    def mass(self, th, q):
        n, N = self.n, self.N
        c, s_ = np.cos(th), np.sin(th)
        C = np.array([[c, -s_], [s_, c]])
        s = np.array([self.S_o, self.Pb @ q])
        Js = np.array([-s[1], s[0]])
        A = np.zeros((N, N))
        A[0:2, 0:2] = self.m * np.eye(2)
        A[0:2, 2] = C @ Js
        A[0:2, 3:] = np.outer(C[:, 1], self.Pb)
        A[2, 2] = self.I_o + q @ self.M @ q
        A[2, 3:] = self.Pt
        A[3:, 3:] = self.M
        A[2:, 0:2] = A[0:2, 2:].T
        A[3:, 2] = A[2, 3:]
        return A, C, s

    def rhs(self, t, x, u):
        n, N = self.n, self.N
        z, zd = x[:N], x[N:]
        th, q = z[2], z[3:]
        Rd, thd, qd = zd[0:2], zd[2], zd[3:]
        A, C, s = self.mass(th, q)
        Mq = self.M @ q
        Pqd = self.Pb @ qd
        # dC/dtheta = C J; J J = -I; C J e2 = -C e1.
        # (dM/dt) z': rows R, theta, q
        #   M_Rtheta' = -theta' C s + C J (0, Phi_bar q') = -theta' C s - (Phi_bar q') C e1
        #   M_Rq'     = theta' C J e2 Phi_bar = -theta' C e1 Phi_bar
        #   M_thetatheta' = 2 q^T M q'
        dRth = -thd * (C @ s) - Pqd * C[:, 0]
        dRq_qd = -thd * Pqd * C[:, 0]
        Mdot_zd = np.zeros(N)
        Mdot_zd[0:2] = dRth * thd + dRq_qd
        Mdot_zd[2] = dRth @ Rd + 2.0 * (Mq @ qd) * thd
        Mdot_zd[3:] = -thd * (C[:, 0] @ Rd) * self.Pb + 0.0
        # dT/dz: dT/dR = 0; dT/dtheta = R'^T (dC/dtheta)(theta' J s + e2 Phi_bar q')
        #   = R'^T C J (theta' J s + e2 Phi_bar q') = R'^T C (-theta' s - e1 Phi_bar q')
        # dT/dq_i = theta' R'^T C J (0, Phi_bar_i) + theta'^2 (M q)_i = -theta' (R'^T C e1) Phi_bar_i + theta'^2 (M q)_i
        dT = np.zeros(N)
        dT[2] = Rd @ (C @ (-thd * s - np.array([Pqd, 0.0])))
        dT[3:] = -thd * (Rd @ C[:, 0]) * self.Pb + thd * thd * Mq
        rhs = u * self.g_torque - Mdot_zd + dT
        rhs[3:] -= self.K @ q
        zdd = np.linalg.solve(A, rhs)
        return np.concatenate((zd, zdd))


def check_rhs(model, path):
    rows = np.loadtxt(path, delimiter=",", ndmin=2)
    N2 = 2 * model.N
    worst = 0.0
    for r in rows:
        u, x, xd = r[0], r[1:1 + N2], r[1 + N2:1 + 2 * N2]
        mine = model.rhs(0.0, x, u)
        worst = max(worst, np.max(np.abs(mine - xd)) / np.max(np.abs(xd)))
    return len(rows), worst


def simulate(model, T, method, rtol, atol):
    pieces = [(0.0, 0.5, 1.0), (0.5, 1.0, -1.0), (1.0, T, 0.0)]
    t_out = np.round(np.arange(0.0, T + 1e-9, 0.01), 10)
    x = np.zeros(2 * model.N)
    out = [x.copy()]
    nfev = 0
    for a, b, u in pieces:
        if b <= a:
            continue
        te = t_out[(t_out > a + 1e-12) & (t_out <= b + 1e-12)]
        sol = solve_ivp(lambda t, y: model.rhs(t, y, u), (a, b), x, method=method, rtol=rtol, atol=atol,
                        t_eval=te, dense_output=False)
        if sol.status != 0:
            raise RuntimeError(f"{method} rtol {rtol}: {sol.message}")
        nfev += sol.nfev
        out.extend(sol.y.T)
        x = sol.y[:, -1].copy()
    return np.array(out), nfev


def main():
    d = sys.argv[1]
    noas = [int(a.split("=")[1]) for a in sys.argv if a.startswith("--noa=")] or [6, 20]
    rtols = [float(r) for a in sys.argv if a.startswith("--rtols=") for r in a.split("=")[1].split(",")]
    print("| NOA | SciPy method | rtol | error θ [rad] | error q | CPU [ms] | RHS evaluations |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for noa in noas:
        data = json.load(open(f"{d}/model_noa{noa}.json"))
        model = FullModel(data)
        count, worst = check_rhs(model, f"{d}/rhs_noa{noa}.csv")
        print(f"NOA {noa}: right-hand side against freeflex at {count} random states: max rel. difference {worst:.1e}",
              file=sys.stderr)
        if not worst < 1e-11:  # round-off of two different solves (measured 1.1e-14, 2.8e-13)
            sys.exit("the right-hand sides differ by more than round-off")
        T = data["duration_s"]
        ref = np.loadtxt(f"{d}/reference_noa{noa}.csv", delimiter=",")
        N = model.N
        if rtols:
            runs = [("DOP853", r) for r in rtols]
        else:
            runs = [("DOP853", r) for r in (1e-6, 1e-8, 1e-10, 1e-12, 1e-13)]
            # Radau with difference-quotient Jacobians is slow in Python (NOA 6: 23 s at 1e-6)
            runs += [("Radau", r) for r in ((1e-6,) if noa == 20 else (1e-6, 1e-8))]
        for method, rtol in runs:
            best = float("inf")
            reps = 1 if (noa >= 20 or rtol < 1e-9 or method == "Radau") else 3
            for _ in range(reps):
                t0 = time.process_time()
                y, nfev = simulate(model, T, method, rtol, rtol * 1e-2)
                best = min(best, time.process_time() - t0)
            et = np.max(np.abs(y[:, 2] - ref[:, 3]))
            eq = np.max(np.abs(y[:, 3:N] - ref[:, 4:4 + model.n]))
            print(f"| {noa} | {method} | {rtol:.3g} | {et:.2g} | {eq:.2g} | {1e3 * best:.4g} | {nfev} |", flush=True)


if __name__ == "__main__":
    main()
