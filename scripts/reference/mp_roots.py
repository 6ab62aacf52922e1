"""Roots of a real characteristic function in high precision (shared by the reference scripts)."""
import mpmath as mp


def bracketed_roots(f, count, k_start, k_step):
    """The first `count` sign changes of f(omega), omega = k^2, polished to working precision.

    The scan runs in k = sqrt(omega) (proportional to the beam's wave number, so the roots
    are about evenly spaced) from k_start by k_step; every bracket with a sign change is
    handed to mpmath's Anderson (bracketing) solver at the caller's mp.dps. A step well
    under the root spacing is the caller's duty; the p-FE cross-check would reveal a
    missed pair of roots.
    """
    roots = []
    k_prev = mp.mpf(k_start)
    f_prev = f(k_prev**2)
    step = mp.mpf(k_step)
    while len(roots) < count:
        k = k_prev + step
        fk = f(k**2)
        if mp.sign(fk) != mp.sign(f_prev):
            roots.append(mp.findroot(f, (k_prev**2, k**2), solver="anderson"))
        k_prev, f_prev = k, fk
    return roots
