import numpy as np, sys
from load import load
np.set_printoptions(linewidth=200, precision=4)
for noa in (6,20):
    D = load(noa); N, n = D['N'], D['n']; m = n+1
    rows = np.vstack(D['P'])
    t, th, w, wd, u = rows[:,:5].T
    M = rows[:,5:]
    print("NOA", noa, "wd/u range", (wd/u).min(), (wd/u).max(), "w range", w.min(), w.max())
    # fit basis 1, w, w^2, u
    X = np.stack([np.ones_like(w), w, w**2, u], 1)
    coef, *_ = np.linalg.lstsq(X, M, rcond=None)
    res = M - X@coef
    print(" fit {1,w,w2,u}: max residual", abs(res).max(), " max |M|", abs(M).max())
    for nm, c in zip(["M0","Mw","Mw2","Mu"], coef):
        C = c.reshape(m,m); print(" ", nm, "norm2 %.3e  max %.3e" % (np.linalg.norm(C,2), abs(C).max()))
    C0 = coef[0].reshape(m,m)
    # expected L: rigid: pos' = vel (rows 0..2 cols N..N+2 = I), elastic eta' = om nu, nu' = -om eta
    ne = N-3
    L = np.zeros((n,n)); L[0:3, N:N+3] = np.eye(3)
    L[3:N, N+3:n] = np.diag(D['om']); L[N+3:n, 3:N] = -np.diag(D['om'])
    print("  |M0[:n,:n] - L| max", abs(C0[:n,:n]-L).max(), " M0 g col", C0[:n, n])
    pass  # (the fitted coefficients are recomputed by filon.setup)
    # check also structure of w-terms restricted
    Mw = coef[1].reshape(m,m); Mw2 = coef[2].reshape(m,m); Mu = coef[3].reshape(m,m)
    print("  Mu nonzero cols outside g:", abs(Mu[:, :n]).max(), " Mu g max", abs(Mu[:,n]).max())
    print("  Mw g", abs(Mw[:,n]).max(), "Mw2 g", abs(Mw2[:,n]).max())
    # where is Mw large?
    A = abs(Mw); i,j = np.unravel_index(A.argmax(), A.shape); print("  Mw max at", i, j, "N", N)
    print("  Mw blocks: rr %.2e re %.2e er %.2e ee %.2e" % (abs(Mw[:6][:, :6]).max(), 0,0,0))
    idx_r = [0,1,2,N,N+1,N+2]; idx_e = [k for k in range(n) if k not in idx_r]
    for nm, C in (("M0-L",np.pad(L,((0,1),(0,1)))-C0), ("Mw",Mw),("Mw2",Mw2),("Mu",Mu)):
        C = C[:n,:n]
        print("   %s: rr %.2e re %.2e er %.2e ee %.2e" % (nm, abs(C[np.ix_(idx_r,idx_r)]).max(), abs(C[np.ix_(idx_r,idx_e)]).max(), abs(C[np.ix_(idx_e,idx_r)]).max(), abs(C[np.ix_(idx_e,idx_e)]).max()))
