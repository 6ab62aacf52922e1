#!/usr/bin/python3
"""Why the free-free FE modes miss a moment at o (issue 15, acceptance 2; docs/theory.md 4b).

Uniform beam, EI = m = L = 1, o at the centre, each side a = 1/2. Under a unit angular
acceleration the deflection relative to o solves EI w'''' = -m x on each side with
w(0) = w'(0) = 0 and a free end: the two cantilevers' static deflection, odd in x, whose
root curvature -a^3/3 jumps in sign across o. Its Rayleigh-Ritz approximation (minimum
of the energy over the span) in n antisymmetric functions of two kinds:
  clamped    the paper's functions sign(x) psi_k(|x|/a) (cantilever modes, eq. 2.1);
  free-free  the antisymmetric free-free modes of the whole beam less their rigid part at
             o (eq. 2.6), smooth through o.
Prints the relative error of the tip deflection and the root curvature at each n. All
functions in mpmath at 40 digits (the textbook forms cancel beyond k ~ 8 in doubles),
integrals by 60 panels of 20-point Gauss-Legendre per side. Run: scripts/reference/
static_ritz_moment_at_o.py (about a minute).
"""
import numpy as np
import mpmath
from mpmath import mp, findroot, cos, cosh, pi
mp.dps = 40
a = 0.5
# exact: for x in [0, a]: EI w'''' = -x, w(0)=w'(0)=0, w''(a)=w'''(a)=0
# w'''(x) = -(x^2 - a^2)/2 ; w''(x) = -(x^3/6 - a^2 x/2) + C, w''(a)=0 -> C = a^3/6 - a^3/2 = -a^3/3
def w_exact(x):
    # integrate w'' = -(x^3/6 - a^2 x /2) - a^3/3 twice from 0
    return -(x**5/120 - a**2*x**3/12) - a**3*x**2/6
curv0 = -a**3/3
# quadrature: Gauss on [0,a] with many panels
g, wg = np.polynomial.legendre.leggauss(20)
P = 60
xs0 = np.concatenate([(i + 0.5 + 0.5*g)/P*a for i in range(P)]);
ws = np.concatenate([0.5*wg/P*a for i in range(P)])
xs = np.array([mpmath.mpf(v) for v in xs0], dtype=object)
for nm in ['cosh','sinh','cos','sin']:
    globals()['np_'+nm] = np.frompyfunc(getattr(mpmath, nm), 1, 1)
def cant(k):
    l = (findroot(lambda t: cos(t) + 1/cosh(t), (2*k-1)*pi/2 if k > 1 else 1.875))
    s = (np_sinh(l) - np_sin(l))/(np_cosh(l) + np_cos(l))
    b = l/mpmath.mpf(a)
    z = b*xs
    f = np_cosh(z) - np_cos(z) - s*(np_sinh(z) - np_sin(z))
    f2 = b*b*(np_cosh(z) + np_cos(z) - s*(np_sinh(z) + np_sin(z)))
    ztip = l
    ftip = mpmath.cosh(ztip) - mpmath.cos(ztip) - s*(mpmath.sinh(ztip) - mpmath.sin(ztip))
    return f.astype(float), f2.astype(float), float(ftip), float(2*b*b)
def ff_anti(k):
    # antisymmetric free-free modes of the beam [-1/2, 1/2]: cos l cosh l = 1, even-numbered roots
    roots = [4.730040744862704, 7.853204624095838, 10.99560783800167, 14.13716549125746]
    idx = 2*k - 1  # antisymmetric: 2nd, 4th, ...
    l = (findroot(lambda t: cos(t) - 1/cosh(t), roots[idx] if idx < 4 else (2*idx+3)*pi/2))
    s = (np_cosh(l) - np_cos(l))/(np_sinh(l) - np_sin(l))
    b = l  # L = 1
    sL = xs + mpmath.mpf(0.5)  # distance from left end for x >= 0
    f = np_cosh(b*sL) + np_cos(b*sL) - s*(np_sinh(b*sL) + np_sin(b*sL))
    f1 = b*(np_sinh(b*sL) - np_sin(b*sL) - s*(np_cosh(b*sL) + np_cos(b*sL)))
    f2 = b*b*(np_cosh(b*sL) - np_cos(b*sL) - s*(np_sinh(b*sL) - np_sin(b*sL)))
    # value and slope at o (sL = 0.5)
    z = b*mpmath.mpf(0.5)
    f0 = mpmath.cosh(z) + mpmath.cos(z) - s*(mpmath.sinh(z) + mpmath.sin(z))
    d0 = b*(mpmath.sinh(z) - mpmath.sin(z) - s*(mpmath.cosh(z) + mpmath.cos(z)))
    g = f - f0 - xs*d0  # rigid part at o removed
    zt = b
    ft = mpmath.cosh(zt) + mpmath.cos(zt) - s*(mpmath.sinh(zt) + mpmath.sin(zt)) - f0 - d0/2
    c0 = b*b*(mpmath.cosh(z) - mpmath.cos(z) - s*(mpmath.sinh(z) - mpmath.sin(z)))
    return g.astype(float), f2.astype(float), float(ft), float(c0)
p = -xs.astype(float)
wt = w_exact(0.5)
print("exact tip deflection (relative to o) %.10f, root curvature %.6f" % (wt, curv0))
for n in [1, 2, 3, 4, 6, 8, 12, 24]:
    out = []
    for kind in (cant, ff_anti):
        F = [kind(k) for k in range(1, n + 1)]
        Ph = np.array([f[0] for f in F]); Ph2 = np.array([f[1] for f in F])
        K = (Ph2*ws) @ Ph2.T; fv = (Ph*ws) @ p
        c = np.linalg.solve(K, fv)
        tip = c @ np.array([f[2] for f in F]); cr = c @ np.array([f[3] for f in F])
        out.append((abs(tip/wt - 1), cr))
    print("antisym functions n=%2d (NOA %2d): clamped tip err %.2e root curv %.6f | free-free tip err %.2e root curv %.6f"
          % (n, 2*n, out[0][0], out[0][1], out[1][0], out[1][1]))
