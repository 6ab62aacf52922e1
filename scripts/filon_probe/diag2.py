# Which couplings matter: drop the entries of B~ (complex modal form) whose interaction-picture
# frequency |lam_k - lam_j| exceeds Omega, integrate with DOP853 (rtol 1e-12) and compare with the
# library reference: the change is the accuracy ceiling of any scheme that does not resolve
# frequencies above Omega (a polynomial y over steps h resolves roughly |Delta| h < d).
import numpy as np, sys, time
from scipy.integrate import solve_ivp
from filon import setup, errors
noa = int(sys.argv[1]); S = setup(noa); n, N = S['n'], S['N']; lam = S['lam']
Omegas = [float(x) for x in sys.argv[2].split(',')]
Dl = abs(lam[None, :] - lam[:, None])
Lm = np.diag(lam) + S['Nsh']
def solve(mask):
    x = np.zeros(n); out = []; nf = 0
    ts = np.round(np.arange(0, 1.0001, 0.005), 10)
    for p in (0, 1):
        Bm = [S['Bt'][p][r] * mask for r in range(3)]; g = S['gt'][p]
        def f(t, x):
            tau = t - 0.5 * p
            B = Bm[0] + tau * Bm[1] + tau * tau * Bm[2]
            return np.real(S['Ti'] @ ((Lm + B) @ (S['Tm'] @ x) + g[0] + tau * g[1] + tau * tau * g[2]))
        te = ts[(ts > 0.5 * p + 1e-9) & (ts < 0.5 * p + 0.5 + 1e-9)]
        sol = solve_ivp(f, (0.5 * p, 0.5 * p + 0.5), x, method='DOP853', rtol=1e-12, atol=1e-15, t_eval=te)
        nf += sol.nfev
        for i, t in enumerate(sol.t):
            xa = S['D']['S'] @ np.concatenate([sol.y[:, i], [1.0]]); out.append((t, xa[2], xa[3:N]))
        x = sol.y[:, -1]
    return out, nf
print(f"NOA {noa}: effect of dropping couplings with |Delta| > Omega (DOP853 rtol 1e-12 vs library reference)")
print("| Omega [rad/s] | kept entries of B | err theta 0.5 | 1.0 | max | err q max | nfev |")
print("|---|---|---|---|---|---|---|")
for Om in Omegas:
    mask = (Dl <= Om).astype(float)
    t0 = time.time(); out, nf = solve(mask); et, eq, mt, mq = errors(S, out)
    print(f"| {Om:g} | {int(mask.sum())}/{n*n} | {et[0.5]:.2e} | {et[1.0]:.2e} | {mt:.2e} | {mq:.2e} | {nf} |", flush=True)
