"""p-version finite elements for a planar Euler-Bernoulli beam (shared by the reference scripts).

Not a reference by itself: stepped_beam_frequencies.py, tapered_beam_frequencies.py and
rotating_cantilever_frequencies.py use it as their Rayleigh-Ritz cross-check.

Method. The beam [0, L] is cut into elements at given points (segment junctions, point
masses). On each element the deflection is a polynomial of degree p in xi in [-1, 1]:
four Hermite cubics carry the nodal deflection w and slope w' (C1 across nodes), and
p - 3 bubbles b_j (j = 2 .. p-2), defined by b_j'' = P_j (Legendre) with b_j = b_j' = 0 at
both ends, enrich the element. The bubbles' curvatures are orthogonal, so the bending
stiffness stays well conditioned up to p ~ 40. All integrals use Gauss-Legendre
quadrature exact for polynomial coefficients of degree <= 4 (so linear or quadratic
mass, stiffness and axial force are integrated exactly). Because the solution is
analytic inside each element, the eigenvalues converge exponentially in p, from above
(Rayleigh-Ritz bound) whenever the stiffness form is positive.

Energy forms (for the eigenproblem K a = omega^2 M a):
    K = int EI w'' dw'' + int N w' dw' - soft * int m w dw    (soft = Omega^2 for in-plane spin)
    M = int m w dw + sum_points (mass w dw + J w' dw')
Boundary: 'free' (nothing) or 'clamped' (w = w' = 0) at x = 0; the right end is free.
"""
import numpy as np
from numpy.polynomial import legendre as npleg
from numpy.polynomial import Legendre
import scipy.linalg


def _element_basis(p):
    """Legendre-series objects for the element shape functions on [-1, 1].

    Order: H1 (w at left), H2 (slope at left, times h/2), H3 (w right), H4 (slope right,
    times h/2), then bubbles j = 2 .. p-2.
    """
    from numpy.polynomial import Polynomial
    herm = [
        Polynomial([2, -3, 0, 1]) / 4,    # (1-x)^2 (2+x)/4
        Polynomial([1, -1, -1, 1]) / 4,   # (1-x)^2 (1+x)/4
        Polynomial([2, 3, 0, -1]) / 4,    # (1+x)^2 (2-x)/4
        Polynomial([-1, -1, 1, 1]) / 4,   # -(1+x)^2 (1-x)/4
    ]
    basis = [h.convert(kind=Legendre) for h in herm]
    for j in range(2, p - 1):
        c = np.zeros(j + 3)
        # b_j = [ (P_{j+2} - P_j)/(2j+3) - (P_j - P_{j-2})/(2j-1) ] / (2j+1)
        c[j + 2] += 1.0 / (2 * j + 3)
        c[j] -= 1.0 / (2 * j + 3)
        c[j] -= 1.0 / (2 * j - 1)
        c[j - 2] += 1.0 / (2 * j - 1)
        c /= (2 * j + 1)
        basis.append(Legendre(c))
    return basis


def assemble(nodes, p, EI, m, N=None, soft=0.0, points=(), clamped_left=False):
    """Global K and M.

    nodes: increasing x of element ends (must contain every point-mass position).
    EI, m, N: vectorised callables of x (N may be None).
    points: iterable of (x, mass, J) at node positions.
    Returns K, M (dense, free DOFs only).
    """
    nodes = np.asarray(nodes, dtype=float)
    ne = len(nodes) - 1
    nb = p - 3                       # bubbles per element
    ndof = 2 * (ne + 1) + nb * ne
    K = np.zeros((ndof, ndof))
    M = np.zeros((ndof, ndof))
    basis = _element_basis(p)
    ng = p + 4
    xg, wg = npleg.leggauss(ng)
    B0 = np.array([b(xg) for b in basis])
    B1 = np.array([b.deriv(1)(xg) for b in basis])
    B2 = np.array([b.deriv(2)(xg) for b in basis])
    for e in range(ne):
        x0, x1 = nodes[e], nodes[e + 1]
        h = x1 - x0
        J = h / 2.0
        x = x0 + (xg + 1.0) * J
        # slope DOFs: the Hermite slope functions multiply (h/2) theta
        scale = np.ones(len(basis))
        scale[1] = J
        scale[3] = J
        b0 = B0 * scale[:, None]
        b1 = B1 * scale[:, None] / J
        b2 = B2 * scale[:, None] / J**2
        wq = wg * J
        ke = (b2 * (EI(x) * wq)) @ b2.T
        if N is not None:
            ke += (b1 * (N(x) * wq)) @ b1.T
        me = (b0 * (m(x) * wq)) @ b0.T
        if soft != 0.0:
            ke -= soft * me
        idx = [2 * e, 2 * e + 1, 2 * e + 2, 2 * e + 3] + \
              [2 * (ne + 1) + nb * e + k for k in range(nb)]
        idx = np.array(idx)
        K[np.ix_(idx, idx)] += ke
        M[np.ix_(idx, idx)] += me
    for (xp, mp_, Jp) in points:
        i = int(np.argmin(np.abs(nodes - xp)))
        if abs(nodes[i] - xp) > 1e-12:
            raise ValueError("point mass at x = %g is not at a node" % xp)
        M[2 * i, 2 * i] += mp_
        M[2 * i + 1, 2 * i + 1] += Jp
    if clamped_left:
        keep = np.arange(2, ndof)
        K = K[np.ix_(keep, keep)]
        M = M[np.ix_(keep, keep)]
    return K, M


def eigenvalues(K, M, count):
    """Lowest `count` eigenvalues omega^2 of K a = omega^2 M a (symmetric, M > 0).

    LAPACK's eigh on the generalized problem has an absolute error ~ eps * lambda_max,
    which for p-elements is far above the low eigenvalues (1e-11 relative at best, worse
    as p grows). So each eigenpair from eigh is polished: two steps of inverse iteration
    with the shift at the eigh value, then the Rayleigh quotient, whose error is the
    square of the eigenvector's (measured: the uniform free-free beam's first five
    frequencies to 1e-15 at p = 14, 4 elements, against 1e-10 from eigh alone).
    """
    K = 0.5 * (K + K.T)
    M = 0.5 * (M + M.T)
    d = 1.0 / np.sqrt(np.diag(M))        # Jacobi scaling: unit mass diagonal
    K = K * d[:, None] * d[None, :]
    M = M * d[:, None] * d[None, :]
    ev, V = scipy.linalg.eigh(K, M, subset_by_index=[0, count - 1])
    out = np.empty(count)
    scale = max(abs(ev[-1]), 1.0)
    for i in range(count):
        x = V[:, i]
        shift = ev[i] + 1e-9 * scale
        lu = scipy.linalg.lu_factor(K - shift * M)
        for _ in range(2):
            x = scipy.linalg.lu_solve(lu, M @ x)
            x /= np.linalg.norm(x)
        out[i] = (x @ K @ x) / (x @ M @ x)
    return out


def hermite_cubics(xi, h):
    """The four Hermite cubics of an element of length h at xi in [0, 1] (nodal values
    and slopes at both ends): values, first and second derivatives along the element.
    Used by the time-domain references (krb_spinup.py, free_spinup.py)."""
    N = np.array([1 - 3 * xi**2 + 2 * xi**3, h * (xi - 2 * xi**2 + xi**3),
                  3 * xi**2 - 2 * xi**3, h * (-xi**2 + xi**3)])
    N1 = np.array([-6 * xi + 6 * xi**2, h * (1 - 4 * xi + 3 * xi**2),
                   6 * xi - 6 * xi**2, h * (-2 * xi + 3 * xi**2)]) / h
    N2 = np.array([-6 + 12 * xi, h * (-4 + 6 * xi), 6 - 12 * xi, h * (-2 + 6 * xi)]) / h**2
    return N, N1, N2
