"""Independent replay of an exported TV-LQR closed loop on the first-order model.

Reads only a freeflex .mat export (scipy.io.loadmat): the model A(t), B(t), g(t) and the
nominal commands u0(t) sampled piece by piece, the gains K(t) and feedforward u_ff(t) on
their grid, the actuator limits. Integrates
    x1' = A x1 + B (sat(u0 + u1) - u0) + g,   u1 = -K(t) x1 + u_ff(t)
by the 4-stage Gauss-Legendre collocation method (order 8, A-stable; freeflex itself uses
CVODES BDF), with fixed steps that subdivide every interval between the gains' grid times
(K is linear between them: TvlqrResult::gain) and the model's pieces. A, B, g, u0 are
interpolated within each piece by cubic splines through its samples. The system is linear
while no command saturates, so each step is one linear solve; with saturation the step
is repeated with the saturated commands held at their limits until the pattern settles.
Usable as a script:  /usr/bin/python3 replay.py controller.mat [substeps]
"""
import sys

import numpy as np
import scipy.io
from scipy.interpolate import CubicSpline

# Gauss-Legendre, 4 stages
_c = np.array([0.5 - np.sqrt(525 + 70 * np.sqrt(30)) / 70, 0.5 - np.sqrt(525 - 70 * np.sqrt(30)) / 70,
               0.5 + np.sqrt(525 - 70 * np.sqrt(30)) / 70, 0.5 + np.sqrt(525 + 70 * np.sqrt(30)) / 70])


def _butcher(c):
    s = len(c)
    # a_ij = integral_0^{c_i} l_j(tau) dtau, b_j = integral_0^1 l_j
    V = np.vander(c, s, increasing=True)  # V[i,k] = c_i^k
    k = np.arange(s)
    Ci = np.array([[ci ** (kk + 1) / (kk + 1) for kk in k] for ci in c])
    A = Ci @ np.linalg.inv(V)
    b = (1.0 / (k + 1)) @ np.linalg.inv(V)
    return A, b


_A, _b = _butcher(_c)


def load(path):
    return scipy.io.loadmat(path, squeeze_me=False)


def replay(d, case="tvlqr_first_order", substeps=5):
    """(output times, replayed x1, exported x1) of the case."""
    A, B, g, u0 = d["A"], d["B"], d["g"], d["u0"]
    n, m = B.shape[0], B.shape[1]
    tm, piece = d["t_model"].ravel(), d["piece"].ravel().astype(int)
    tg, K, uff = d["t_gain"].ravel(), d["K"], d["u_ff"]
    limits = d["limits"].ravel()
    t_out = d[case + "_t"].ravel()
    x1_ref = d[case + "_x1"]

    def gain(t):
        if t <= tg[0]:
            return K[:, :, 0], uff[0]
        if t >= tg[-1]:
            return K[:, :, -1], uff[-1]
        i = min(np.searchsorted(tg, t, side="right") - 1, len(tg) - 2)
        w = (t - tg[i]) / (tg[i + 1] - tg[i])
        return (1 - w) * K[:, :, i] + w * K[:, :, i + 1], (1 - w) * uff[i] + w * uff[i + 1]

    s = len(_c)
    x = np.zeros(n)
    states = {0.0: x.copy()}
    for p in np.unique(piece):
        sel = piece == p
        ts = tm[sel]
        a, b = ts[0], ts[-1]
        if len(ts) >= 4:
            sA = CubicSpline(ts, np.moveaxis(A[:, :, sel], 2, 0), axis=0)
            sB = CubicSpline(ts, np.moveaxis(B[:, :, sel], 2, 0), axis=0)
            sg, su = CubicSpline(ts, g[sel], axis=0), CubicSpline(ts, u0[sel], axis=0)
        else:
            raise RuntimeError(f"piece {p} has {len(ts)} samples; export with a smaller model_step_s")
        edges = np.union1d(np.concatenate(([a, b], tg[(tg > a) & (tg < b)])), t_out[(t_out > a) & (t_out < b)])

        def saturated(t, x1):
            Kt, fft = gain(t)
            return np.abs(su(t) - Kt @ x1 + fft) > limits

        def step(t0, h, x):
            """One Gauss step; (x at t0 + h, whether the saturation pattern held still)."""
            tt = t0 + _c * h
            As, Bs, gs, us = sA(tt), sB(tt), sg(tt), su(tt)
            gains = [gain(t) for t in tt]
            held = np.tile(saturated(t0, x), (s, 1))  # saturated commands, held at their limit
            level = np.zeros((s, m))
            for j in range(s):
                level[j] = np.clip(us[j] - gains[j][0] @ x + gains[j][1], -limits, limits)
            for _ in range(20):
                M, f = [], []
                for j in range(s):
                    Kj, ffj = gains[j]
                    Kj = np.where(held[j][:, None], 0.0, Kj)
                    c = np.where(held[j], np.sign(level[j]) * limits - us[j], ffj)  # u1 at x1 = 0
                    M.append(As[j] - Bs[j] @ Kj)
                    f.append(Bs[j] @ c + gs[j])
                big = np.eye(s * n)
                rhs = np.tile(x, s)
                for i in range(s):
                    for j in range(s):
                        big[i * n:(i + 1) * n, j * n:(j + 1) * n] -= h * _A[i, j] * M[j]
                        rhs[i * n:(i + 1) * n] += h * _A[i, j] * f[j]
                X = np.linalg.solve(big, rhs).reshape(s, n)
                dem = np.array([us[j] - gains[j][0] @ X[j] + gains[j][1] for j in range(s)])
                new_held = np.abs(dem) > limits
                if (new_held == held).all():
                    break
                held, level = new_held, dem
            F = np.array([M[j] @ X[j] + f[j] for j in range(s)])
            x_new = x + h * (_b @ F)
            pattern = np.vstack([saturated(t0, x), held, saturated(t0 + h, x_new)])
            return x_new, bool((pattern == pattern[0]).all())

        def advance(t0, h, x, depth=0):
            # a step across a saturation switch is split until it is 2^-40 of its size
            x_new, smooth = step(t0, h, x)
            if smooth or depth >= 40:
                return x_new
            x_mid = advance(t0, h / 2, x, depth + 1)
            return advance(t0 + h / 2, h / 2, x_mid, depth + 1)

        for e0, e1 in zip(edges[:-1], edges[1:]):
            h = (e1 - e0) / substeps
            for k in range(substeps):
                x = advance(e0 + k * h, h, x)
            states[float(e1)] = x.copy()
    keys = np.array(sorted(states))
    rows = []
    for t in t_out:
        j = np.argmin(np.abs(keys - t))
        if abs(keys[j] - t) > 1e-9:
            raise RuntimeError(f"no replayed state at t = {t}")
        rows.append(states[keys[j]])
    return t_out, np.array(rows), x1_ref


def agreement(d, **kw):
    """max |x1_replay - x1_freeflex| over the output times, absolute and relative to max |x1|."""
    t, x1, ref = replay(d, **kw)
    err = np.abs(x1 - ref).max()
    return err, err / np.abs(ref).max()


if __name__ == "__main__":
    d = load(sys.argv[1])
    sub = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    err, rel = agreement(d, substeps=sub)
    print(f"substeps {sub}: max |x1_replay - x1_freeflex| = {err:.3e}, relative to max |x1| = {rel:.3e}")
