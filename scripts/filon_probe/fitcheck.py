import numpy as np
from load import load
np.set_printoptions(linewidth=220, precision=2)
for noa in (6,20):
    D = load(noa); N,n = D['N'], D['n']; m=n+1
    for p in (0,1):
        R = D['P'][p]; t = R[:,0]; M = R[:,5:]; w = R[:,2]
        for deg in (1,2,3):
            V = np.vander(t-0.5*p-0.25, deg+1, increasing=True)
            c,*_ = np.linalg.lstsq(V, M, rcond=None); res = M - V@c
            Mr = res.reshape(-1,m,m)
            print(noa, p, deg, "resid max %.2e" % abs(res).max(), "where", np.unravel_index(abs(Mr).max(axis=0).argmax(), (m,m)))
        print("   w linear resid", abs(w - np.polyval(np.polyfit(t,w,1),t)).max())
    coef = np.load(f"d{noa}/coef.npy"); K2 = coef[2].reshape(m,m)
    ne=N-3; E = list(range(3,N))+list(range(N+3,n))
    print(" K2 ee (rows eta..nu, cols eta..nu) abs, first 8 modes:")
    print(abs(K2[np.ix_(E,E)])[:, :][ne:ne+8, :8])
    print(" K2 eta-rows max", abs(K2[np.ix_(E[:ne],E)]).max(), " nu-rows-eta-cols diag", np.diag(K2[np.ix_(E[ne:],E[:ne])]))
