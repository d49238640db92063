"""Independent linear theory of a tank section's sloshing under a prescribed roll (no jaxslosh
imports): the modal response of the 2-D potential-flow modes of tests/sloshing_reference.py.

The section lies in the vessel's y-z plane (y across, z up, s = y - y0 and z = zeta + z0 with
(y0, z0) the section's corner), and the vessel rolls by theta(t) about the x axis through the
vessel frame's origin. Relative to the tank, the liquid feels per unit mass the body force

    a = g_b + (g, not its static part) - alpha x r = (-g theta + theta'' z, -theta'' y)    (y, z),

linear in theta: the tilted gravity R^T (0, 0, -g) less its static part, and the frame's angular
acceleration (the centripetal and Coriolis terms are second order). An ideal liquid's relative
displacement is u = sum_n q_n phi_n plus a divergence-free part tangent to every boundary (the
flow that keeps the absolute motion irrotational, Kelvin), which moves no free surface and is
orthogonal to every mode. With mass-normalised modes phi_n = grad(psi_n) / N_n,
N_n^2 = int |grad psi_n|^2 dA (Steklov eigenvectors psi_n of sloshing_reference: omega_n^2 / g =
lambda_n), each mode is a damped oscillator

    q_n'' + 2 zeta omega_n q_n' + omega_n^2 q_n = int phi_n . a dA,

and the surface rises by u_z = sum_n q_n d(psi_n)/dz / N_n = sum_n q_n lambda_n psi_n / N_n there
(the free-surface condition). For theta = Theta exp(i Omega t) the steady amplitude of q_n is
Theta int phi_n . (-g - Omega^2 z, Omega^2 y) dA / (omega_n^2 - Omega^2 + 2 i zeta omega_n Omega).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

try:
    import sloshing_reference as ref
except ImportError:     # imported as tests.u_tube_response from the repository root (benchmarks/validation/)
    from tests import sloshing_reference as ref


def section_modes(rects, fill_depth: float, n: int, h_target: float, g: float = ref.G):
    """(omega (n,), basis (skfem P2), psi (N, n) normalised to int |grad psi|^2 = 1, lambda (n,))
    of the liquid in a union of rectangles (sloshing_reference.rectilinear_section_mesh)."""
    from skfem import Basis, BilinearForm, ElementTriP2
    from skfem.helpers import dot, grad

    m = ref.rectilinear_section_mesh(rects, fill_depth, h_target)

    @BilinearForm
    def laplace(u, v, _):
        return dot(grad(u), grad(v))

    basis = Basis(m.mesh, ElementTriP2())
    K = laplace.assemble(basis).tocsr()
    B = ref._surface_mass(m, basis, 2)
    c = 1.0 / m.width
    lu = spla.splu((K + c * B).tocsc())
    F = basis.get_dofs(m.surface).all()

    def surface_solve(x):
        rhs = np.zeros(basis.N)
        rhs[F] = np.ravel(x)
        return lu.solve(rhs)[F]

    # the surface problem as sloshing_reference solves it (shift-invert about -c), then each mode
    # carried into the liquid: (K + c B) psi = (lambda + c) B psi
    op = spla.LinearOperator((F.size, F.size), matvec=surface_solve, dtype=float)
    k = n + m.pools
    lam, XF = spla.eigsh(op, k=k, M=B[F][:, F].tocsc(), sigma=-c, which="LM", OPinv=op,
                         ncv=max(2 * k + 1, 20), v0=np.random.default_rng(0).standard_normal(F.size))
    order = np.argsort(lam)[m.pools:]
    lam, XF = lam[order], XF[:, order]
    X = np.zeros((basis.N, len(lam)))
    X[F] = XF
    X = np.stack([(l + c) * lu.solve(B @ x) for l, x in zip(lam, X.T)], axis=1)
    X /= np.sqrt(np.einsum("in,in->n", X, K @ X))
    return np.sqrt(g * lam), basis, X, lam


def roll_exchange(rects, fill_depth: float, corner, s_left: float, s_right: float, Omega, zeta: float,
                  n: int = 24, h_target: float = 0.05, g: float = ref.G):
    """The complex amplitude, per radian of roll, of the exchange u_z(s_left) - u_z(s_right) (the
    surface's rise relative to the tank at two points of the free surface) in the steady state of
    theta = exp(i Omega t), every mode damped by the ratio zeta. Also returns the modes' omega."""
    from skfem import LinearForm
    from skfem.helpers import grad

    omega, basis, psi, lam = section_modes(rects, fill_depth, n, h_target, g)
    y0, z0 = corner

    @LinearForm
    def tilt(v, w):                     # int grad v . (-1, 0)
        return -grad(v)[0]

    @LinearForm
    def spin(v, w):                     # int grad v . (-z, y) in the vessel's coordinates
        y, z = w.x[0] + y0, w.x[1] + z0
        return -grad(v)[0] * z + grad(v)[1] * y

    F1 = psi.T @ tilt.assemble(basis)
    F2 = psi.T @ spin.assemble(basis)
    pts = np.array([[s_left, s_right], [fill_depth, fill_depth]])
    P = basis.probes(pts)                                   # (2, N) interpolation at the two points
    rise = lam[None, :] * (P @ psi)                         # (2, n) u_z = lambda psi / N on the surface
    out = []
    for W in np.atleast_1d(Omega):
        q = (g * F1 + W * W * F2) / (omega ** 2 - W * W + 2j * zeta * omega * W)
        out.append((rise[0] - rise[1]) @ q)
    return np.array(out), omega
