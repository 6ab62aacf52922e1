# unit checks of the stepper on sub-systems against DOP853 on the same sub-system
import numpy as np, sys
from scipy.integrate import solve_ivp
from filon import setup, Stepper, shift_poly
noa = int(sys.argv[1]); S0 = setup(noa); n, N = S0['n'], S0['N']
idx_r = [0,1,2,N,N+1,N+2]; idx_e = [k for k in range(n) if k not in idx_r]
def variant(mask):
    S = dict(S0); S['Bt'] = [b * mask[None] for b in S0['Bt']]; return S
def real_rhs(S, p):
    # x' = Re(Ti (Lm + B~(tau)) Tm x + Ti g~)
    Lm = np.diag(S['lam']) + S['Nsh']
    def f(t, x):
        tau = t - 0.5*p
        B = sum(S['Bt'][p][r] * tau**r for r in range(3)); g = sum(S['gt'][p][r] * tau**r for r in range(3))
        return np.real(S['Ti'] @ ((Lm + B) @ (S['Tm'] @ x) + g))
    return f
masks = {'none': np.zeros((n,n)), 'ee': np.zeros((n,n)), 're+rr': np.zeros((n,n)), 'all': np.ones((n,n))}
masks['ee'][np.ix_(idx_e, idx_e)] = 1
masks['re+rr'][idx_r, :] = 1
for name, mk in masks.items():
    S = variant(mk)
    x = np.zeros(n)
    for p in (0,):
        sol = solve_ivp(real_rhs(S, p), (0, 0.5), x, method='DOP853', rtol=1e-12, atol=1e-14)
    xr = sol.y[:, -1]
    for steps, d in ((10, 6), (40, 6), (400, 4)):
        st = Stepper(S, 0.5/steps, d, 'gauss'); w = np.zeros(n, complex)
        for k in range(steps): w = st.step(w, 0, k*0.5/steps)
        x = np.real(S['Ti'] @ w)
        print(f"{name:6s} steps {steps} d {d}: err rigid {abs(x-xr)[idx_r].max():.2e} elastic {abs(x-xr)[idx_e].max():.2e}  |x| rigid {abs(xr[idx_r]).max():.2e} el {abs(xr[idx_e]).max():.2e}")
