# magnitudes per mode (NOA from argv): omega, torque-step static amplitude |g~_j|/omega_j (a-units),
# and the centrifugal coupling at w = 6 rad/s: self |B_{a_j a_j}|, self sum-frequency |B_{a_j b_j}|, row sum over other modes
import numpy as np, sys
from filon import setup
noa = int(sys.argv[1]); S = setup(noa); n, N = S['n'], S['N']; ne = N - 3; om = S['om']
B = S['Bt'][0]; g = S['gt'][0][0]
# B~ in piece 0: M(tau) with w = 12 tau -> w^2 term is B[2] / 144 * 36 at w = 6
B2 = B[2] / 144.0 * 36.0
a = np.arange(3, N); b = np.arange(N + 3, n)
print("| mode | omega | static amp |g_j|/omega_j | |B a_j a_j| (w=6) | |B a_j b_j| (Delta = 2 omega_j) | sum_k!=j |B a_j,(a|b)_k| | share of that sum with |Delta|>5000 |")
print("|---|---|---|---|---|---|---|")
for j in range(ne):
    row = np.abs(B2[a[j]]); others = row.copy(); others[[a[j], b[j]]] = 0
    Dl = np.abs(S['lam'] - S['lam'][a[j]]); far = others[Dl > 5000].sum()
    print(f"| {j+1} | {om[j]:.1f} | {abs(g[a[j]])/om[j]:.2e} | {row[a[j]]:.3g} | {row[b[j]]:.3g} | {others.sum():.3g} | {far:.3g} |")
