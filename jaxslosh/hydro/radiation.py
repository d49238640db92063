"""The radiation memory of the Cummins equation, fitted on the host, and the frequency-domain
response of the hull that the tests and notebooks compare with.

The memory is a state-space model fitted once on the host: for each moving dof j (a column of
K), a common set of complex poles p_k is fitted by vector fitting (Gustavsen & Semlyen 1999) to
K_ij(iw) = B_ij(w) + i w (A_ij(w) - A_inf,ij) over the tabulated frequencies (with A_inf fitted as
well when not given), so K_ij(t) = sum_k Re(c_ik exp(p_k t)). Each pole carries a complex state
w_k' = p_k w_k + xi_dot_j, and mu_i = sum_k Re(c_ik w_k). The states live in the integrator's State;
a step advances them exactly for a velocity linear over the step (first-order hold), so the new
states, hence mu_{n+1}, are linear in the step's unknown new velocity and enter the Newton residual.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np


class RadiationFit(NamedTuple):
    """The fitted memory on the host: per state k, pole p[k] (complex), input dof inp[k], output
    coefficients c[:, k] (n, complex); A_inf (n, n); and the fit's relative error per column. n is 6
    for one body, 6 per body for the coupled radiation of several (physics/bodies.py)."""
    p: np.ndarray
    inp: np.ndarray
    c: np.ndarray
    added_mass_infinite: np.ndarray
    error: np.ndarray      # (n,) max |K_fit - K| / max |K| over the table, per column (0 for a column without memory)

    def kernel_frequency(self, omega):
        """K(iw) of the fit (n, 6, 6): sum_k c_ik / (i w - p_k) (both conjugates of a complex pole)."""
        s = 1j * np.asarray(omega, dtype=float)[:, None]
        n = self.c.shape[0]
        out = np.zeros((s.shape[0], n, n), dtype=complex)
        for j in range(n):
            m = self.inp == j
            if not m.any():
                continue
            p, c = self.p[m], self.c[:, m]
            real = np.abs(p.imag) == 0
            terms = c[None, :, :] * np.where(real, 1.0 / (s - p[None, :]),
                                             0.5 * (1.0 / (s - p[None, :])))[:, None, :]
            conj = np.where(real, 0.0, 0.5 / (s - np.conj(p)[None, :]))[:, None, :] * np.conj(c)[None, :, :]
            out[:, :, j] = (terms + conj).sum(axis=2)
        return out

    def added_mass(self, omega):
        w = np.asarray(omega, dtype=float)
        return self.added_mass_infinite[None] + (self.kernel_frequency(w).imag / w[:, None, None])

    def damping(self, omega):
        return self.kernel_frequency(omega).real

    def kernel(self, t):
        """K(t) (n, 6, 6)."""
        t = np.asarray(t, dtype=float)
        n = self.c.shape[0]
        out = np.zeros((t.size, n, n))
        for k in range(self.p.size):
            out[:, :, self.inp[k]] += np.real(self.c[None, :, k] * np.exp(self.p[k] * t)[:, None])
        return out


def _vf_basis(s, poles):
    """Real basis for vector fitting: one column per real pole, two per complex pair (the pair
    (a, conj a) written as 1/(s-a) + 1/(s-a*) and i/(s-a) - i/(s-a*))."""
    cols = []
    for a in poles:
        if a.imag == 0:
            cols.append(1.0 / (s - a))
        else:
            cols.append(1.0 / (s - a) + 1.0 / (s - np.conj(a)))
            cols.append(1j / (s - a) - 1j / (s - np.conj(a)))
    return np.stack(cols, axis=1)


def vector_fit(omega, F, n_pairs, with_e=False, iterations=15, weight=None):
    """Common-pole rational fit F_i(iw) ~ sum_k r_ik / (iw - a_k) (+ iw e_i) of the columns of
    F (n, m) complex (Gustavsen & Semlyen 1999; unstable poles flipped). Returns poles (one of each
    conjugate pair, complex), residues (m, poles) complex for those poles (the conjugate pole carries
    the conjugate residue), e (m,), and the relative max error of each column."""
    w = np.asarray(omega, dtype=float)
    s = 1j * w
    n, m = F.shape
    scale = np.maximum(np.abs(F).max(axis=0), 1e-300)
    Fn = F / scale
    W = np.ones(n) if weight is None else np.asarray(weight, dtype=float)
    beta = np.linspace(w.min(), w.max(), n_pairs) if n_pairs > 1 else np.array([np.sqrt(w.min() * w.max())])
    poles = -0.05 * beta + 1j * beta
    for _ in range(iterations):
        Phi = _vf_basis(s, poles)                       # (n, N)
        N = Phi.shape[1]
        extra = [s[:, None]] if with_e else []
        rows = []
        rhs = []
        for i in range(m):
            own = np.concatenate([Phi] + extra, axis=1) if extra else Phi
            blocks = np.zeros((n, m * own.shape[1] + N), dtype=complex)
            blocks[:, i * own.shape[1]:(i + 1) * own.shape[1]] = own
            blocks[:, m * own.shape[1]:] = -Fn[:, i:i + 1] * Phi
            rows.append(W[:, None] * blocks)
            rhs.append(W * Fn[:, i])
        Acm = np.concatenate(rows)
        b = np.concatenate(rhs)
        Ar = np.concatenate([Acm.real, Acm.imag])
        br = np.concatenate([b.real, b.imag])
        sol = np.linalg.lstsq(Ar, br, rcond=None)[0]
        ct = sol[-N:]
        # zeros of sigma = eig(A - b c^T) in real block form
        Ab = np.zeros((N, N))
        bb = np.zeros(N)
        col = 0
        for a in poles:
            if a.imag == 0:
                Ab[col, col] = a.real
                bb[col] = 1.0
                col += 1
            else:
                Ab[col:col + 2, col:col + 2] = [[a.real, a.imag], [-a.imag, a.real]]
                bb[col] = 2.0
                col += 2
        z = np.linalg.eigvals(Ab - np.outer(bb, ct))
        z = np.where(z.real > 0, -z.real + 1j * z.imag, z)
        z = np.where(np.abs(z.real) < 1e-6 * np.abs(z), -1e-6 * np.abs(z) + 1j * z.imag, z)
        keep = [x for x in z if x.imag > 0] + [x for x in z if x.imag == 0]
        poles = np.array(keep, dtype=complex)
    # residues with the final poles
    Phi = _vf_basis(s, poles)
    own = np.concatenate([Phi, s[:, None]], axis=1) if with_e else Phi
    res = np.zeros((m, poles.size), dtype=complex)
    e = np.zeros(m)
    err = np.zeros(m)
    for i in range(m):
        Ai = W[:, None] * own
        sol = np.linalg.lstsq(np.concatenate([Ai.real, Ai.imag]),
                              np.concatenate([(W * Fn[:, i]).real, (W * Fn[:, i]).imag]), rcond=None)[0]
        col = 0
        for k, a in enumerate(poles):
            if a.imag == 0:
                res[i, k] = sol[col]
                col += 1
            else:
                res[i, k] = sol[col] + 1j * sol[col + 1]
                col += 2
        if with_e:
            e[i] = sol[-1]
        err[i] = np.abs(own @ sol - Fn[:, i]).max()
    return poles, res * scale[:, None], e * scale, err


def fit_tables(tables, T=None, skip=None, order: int = 0):
    """The memory fit (`fit_radiation`) of hydrodynamic tables (hydro/tables.py Tables) over their
    dofs: the one path of the vessel's own tables (hydro/source.py radiation_fit) and of the bodies'
    sources (assemble/bodyhydro.py source_fit). `T` (d, d): the step's dofs -> the tables' (A in the
    step's dofs is T^T A T; None: the tables' own axes, as given); `skip`: entries left out; `order`:
    pole pairs per entry (0: automatic, the scene's `memory_order`). None without radiation tables."""
    if tables.added_mass is None:
        return None
    turn = (lambda A: A) if T is None else (lambda A: np.einsum("ki,...kl,lj->...ij", T, A, T))  # noqa: E731
    Ainf = tables.added_mass_infinite
    return fit_radiation(tables.omega, turn(tables.added_mass), turn(tables.damping),
                         None if Ainf is None else turn(Ainf), order=order, skip=skip)


def fit_radiation(omega, added_mass, damping, added_mass_infinite=None, order: int = 0, tol: float = 0.005,
                  max_pairs: int = 12, threshold: float = 1e-2, skip=None):
    """Fit the memory to tables A(w), B(w) (n, d, d) about the COG (d = 6, or 6 per body of a
    multibody database); returns a RadiationFit. `skip` (d, d) bool: entries left out (zero in
    the fit: another term carries them).

    Each entry with memory (its |B_ij| or w |A_ij(w) - A_inf,ij| above `threshold` times the
    geometric mean of the two diagonal entries' sizes) is fitted on its own (vector fitting of one
    function): `order` complex pole pairs, or (order = 0) the fewest from 1 to `max_pairs` whose
    error is below `tol` (relative max over the table; the best tried otherwise). The symmetric
    part of the tables is fitted (A_ij = A_ji, B_ij = B_ji at zero speed), and the fit of (i, j)
    serves (j, i). A_inf is the given value or one fitted with the poles (see below)."""
    w = np.asarray(omega, dtype=float)
    A = np.asarray(added_mass, dtype=float)
    B = np.asarray(damping, dtype=float)
    A = 0.5 * (A + A.transpose(0, 2, 1))
    B = 0.5 * (B + B.transpose(0, 2, 1))
    known = added_mass_infinite is not None
    Ainf = 0.5 * (np.array(added_mass_infinite, dtype=float) + np.array(added_mass_infinite, dtype=float).T) \
        if known else A[-1].copy()
    size = np.maximum(np.abs(B).max(axis=0), w.max() * np.abs(A - Ainf[None]).max(axis=0))   # (6, 6)
    dsize = np.diag(size)
    d = A.shape[1]
    skip = np.zeros((d, d), dtype=bool) if skip is None else np.asarray(skip, dtype=bool)
    Ainf[skip] = 0.0
    poles, inps, cs = [], [], []
    err = np.zeros(d)
    for i in range(d):
        for j in range(i, d):
            ref = np.sqrt(dsize[i] * dsize[j])
            if skip[i, j] or ref <= 0 or size[i, j] <= threshold * ref:
                continue
            # A_inf,ij: the given value, or the one fitted with the poles (as the coefficient of i w), whichever
            # leaves the smaller error: a value inconsistent with band-limited tables (an off-diagonal term
            # that converges slowly) would leave w (A - A_inf) growing across the band, which no memory fits
            cands = [Ainf[i, j]] if known else []
            _, _, e_fit, _ = vector_fit(w, (B[:, i, j] + 1j * w * A[:, i, j])[:, None], max(order, 4), with_e=True)
            cands.append(e_fit[0])
            best = None
            for a_inf in cands:
                F = B[:, i, j] + 1j * w * (A[:, i, j] - a_inf)
                for npairs in ([order] if order else list(range(1, max_pairs + 1))):
                    p, r, _, er = vector_fit(w, F[:, None], npairs)
                    if best is None or er.max() < best[2].max():
                        best = (p, r, er, a_inf)
                    if er.max() <= tol:
                        break
            p, r, er, a_inf = best
            err[i] = max(err[i], er.max())
            err[j] = max(err[j], er.max())
            Ainf[i, j] = Ainf[j, i] = a_inf
            for (out, inp) in ({(i, j), (j, i)}):
                for k in range(p.size):
                    c = np.zeros(d, dtype=complex)
                    c[out] = r[0, k] if p[k].imag == 0 else 2.0 * r[0, k]   # a pair: Re(2 r e^{pt})
                    poles.append(p[k])
                    inps.append(inp)
                    cs.append(c)
    c = np.array(cs).T if cs else np.zeros((d, 0), dtype=complex)
    return RadiationFit(np.array(poles, dtype=complex), np.array(inps, dtype=int), c, Ainf, err)


def linear_response(omega, mass, C, A, B, F):
    """xi = [C - w^2 (M + A) + i w B]^-1 F at each frequency: (n, 6) complex for M (6, 6), C (6, 6),
    A, B (n, 6, 6) and F (n, 6) complex (forces per unit wave amplitude: the RAOs). Rows and
    columns of dofs that nothing restrains or loads are solved as they come (sway, surge, yaw
    have no restoring but inertia and damping)."""
    w = np.atleast_1d(np.asarray(omega, dtype=float))
    out = np.zeros((w.size, 6), dtype=complex)
    for i, wi in enumerate(w):
        Z = C - wi * wi * (mass + A[i]) + 1j * wi * B[i]
        out[i] = np.linalg.solve(Z, F[i])
    return out


def rigid_mass_matrix(mass, inertia):
    M = np.zeros((6, 6))
    M[:3, :3] = mass * np.eye(3)
    M[3:, 3:] = np.asarray(inertia, dtype=float)
    return M


def restoring_matrix(rho, g, waterplane_area, displaced_volume, gm_t, gm_l):
    """The linear restoring of model.Hydro (heave, roll, pitch; no coupling)."""
    C = np.zeros((6, 6))
    C[2, 2] = rho * g * waterplane_area
    C[3, 3] = rho * g * displaced_volume * gm_t
    C[4, 4] = rho * g * displaced_volume * gm_l
    return C
