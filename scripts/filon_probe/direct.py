# sanity: integrate x' = M(t) [x;1] with the fitted M directly (DOP853), compare with the library reference
import numpy as np, sys
from scipy.integrate import solve_ivp
from filon import setup, shift_poly
noa = int(sys.argv[1]); S = setup(noa); D = S['D']; n, N = S['n'], S['N']
from load import load
coefs = []
for p in (0, 1):
    R = D['P'][p]; t = R[:, 0] - 0.5 * p
    c, *_ = np.linalg.lstsq(np.vander(t, 3, increasing=True), R[:, 5:], rcond=None); coefs.append(c.reshape(3, n+1, n+1))
x = np.zeros(n); ts = np.arange(0, 1.0001, 0.005); out = []
for p in (0, 1):
    f = lambda t, x: (coefs[p][0] + (t-0.5*p)*coefs[p][1] + (t-0.5*p)**2*coefs[p][2])[:n] @ np.concatenate([x, [1.0]])
    te = ts[(ts > 0.5*p + 1e-9) & (ts < 0.5*p + 0.5 + 1e-9)]
    sol = solve_ivp(f, (0.5*p, 0.5*p+0.5), x, method='DOP853', rtol=1e-12, atol=1e-14, t_eval=te)
    print("nfev", sol.nfev)
    for i, t in enumerate(sol.t):
        xa = D['S'] @ np.concatenate([sol.y[:, i], [1.0]]); out.append((t, xa[2], xa[3:N]))
    x = sol.y[:, -1]
from filon import errors
print(errors(S, out))
print("theta1, q at 0.5, 1.0:", [(o[0], o[1], abs(o[2]).max()) for o in out if abs(o[0]-0.5)<1e-9 or abs(o[0]-1)<1e-9])
