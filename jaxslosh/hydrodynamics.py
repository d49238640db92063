"""Hull hydrodynamics: added mass, radiation damping with the memory of the Cummins equation, wave
excitation from tables, and Capytaine (an optional extra) to compute them.

The rigid rows of the residual (model.System.residual) gain, for small motions xi about the
initial equilibrium (translations of the COG, rotations about it):

    A_inf xi_ddot + mu(t) + B_v xi_dot - F_exc(t),     mu(t) = int_0^t K(t - s) xi_dot(s) ds   (Cummins 1962)

with A_inf the added mass at infinite frequency, K the retardation functions, B_v an optional linear
(viscous) damping and F_exc the first-order wave excitation (waves.py). Coefficients are about the
COG, in the axes of the residual's rows (translations inertial, rotations body: equal at small
motions). In the frequency domain this is the classical

    [-w^2 (M + A(w)) + i w (B(w) + B_v) + C] xi = F_exc,   A(w) = A_inf - int K sin / w,  B(w) = int K cos,

which the tests check against the time-domain run.

The memory is a state-space model fitted once on the host: for each moving dof j (a column of
K), a common set of complex poles p_k is fitted by vector fitting (Gustavsen & Semlyen 1999) to
K_ij(iw) = B_ij(w) + i w (A_ij(w) - A_inf,ij) over the tabulated frequencies (with A_inf fitted as
well when not given), so K_ij(t) = sum_k Re(c_ik exp(p_k t)). Each pole carries a complex state
w_k' = p_k w_k + xi_dot_j, and mu_i = sum_k Re(c_ik w_k). The states live in the integrator's State;
a step advances them exactly for a velocity linear over the step (first-order hold), so the new
states, hence mu_{n+1}, are linear in the step's unknown new velocity and enter the Newton residual.
"""
from __future__ import annotations

import functools
from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .waves import DOFS, Excitation

# --------------------------------------------------------------------------------------------
# The traced part


class Memory(eqx.Module):
    """The fitted radiation memory: complex poles (real, imaginary parts), their input dof (a one-hot
    (M, 6) selection) and output coefficients c (6, M)."""
    p_re: jax.Array
    p_im: jax.Array
    select: jax.Array     # (M, 6)
    c_re: jax.Array       # (6, M)
    c_im: jax.Array

    def init(self):
        return jnp.zeros((self.p_re.shape[0], 2))

    def coefficients(self, h):
        """exp(p h), g0, g1 of w_{n+1} = exp(p h) w_n + g0 u_n + g1 u_{n+1} (u linear over the step):
        g1 = ((exp(p h) - 1) / (p h) - 1) / p, g0 = (exp(p h) - 1) / p - g1. As (re, im) pairs."""
        p = self.p_re + 1j * self.p_im
        ph = p * h
        E = jnp.exp(ph)
        em1 = jnp.expm1(ph)
        small = jnp.abs(ph) < 1e-4
        phs = jnp.where(small, 1.0, ph)
        ratio = jnp.where(small, 1.0 + ph / 2.0 + ph * ph / 6.0, em1 / phs)   # (e^{ph} - 1) / (ph)
        g1 = jnp.where(small, h * (0.5 + ph / 6.0 + ph * ph / 24.0), (ratio - 1.0) / jnp.where(small, 1.0, p))
        g0 = h * ratio - g1
        split = lambda z: (jnp.real(z), jnp.imag(z))  # noqa: E731
        return split(E), split(g0), split(g1)

    def advance(self, z, v_old, v_new, coef):
        """The states at t_{n+1} from those at t_n and the rigid velocities (6,) at both ends."""
        (Er, Ei), (g0r, g0i), (g1r, g1i) = coef
        u0, u1 = self.select @ v_old, self.select @ v_new
        wr, wi = z[:, 0], z[:, 1]
        nr = Er * wr - Ei * wi + g0r * u0 + g1r * u1
        ni = Er * wi + Ei * wr + g0i * u0 + g1i * u1
        return jnp.stack([nr, ni], axis=1)

    def force(self, z):
        """mu = sum_k Re(c_k w_k) (6,)."""
        return self.c_re @ z[:, 0] - self.c_im @ z[:, 1]


class Seakeeping(eqx.Module):
    """Wave loads and hull hydrodynamics on the rigid rows (see the module docstring); each part is
    None when the scene lacks it or switches it off ([effects] waves, radiation), and is not traced."""
    excitation: Optional[Excitation] = None
    added_mass: Optional[jax.Array] = None     # (6, 6) A_inf about the COG
    damping: Optional[jax.Array] = None        # (6, 6) linear (viscous) damping B_v
    memory: Optional[Memory] = None

    def rigid_rows(self, acc6, v6, t, mu=None):
        """What the hydrodynamics add to the rigid rows of the residual (inertia minus forces)."""
        r = jnp.zeros(6)
        if self.added_mass is not None:
            r = r + self.added_mass @ acc6
        if self.damping is not None:
            r = r + self.damping @ v6
        if self.memory is not None and mu is not None:
            r = r + mu
        if self.excitation is not None:
            r = r - self.excitation.force(t)
        return r

    def added_mass_diagonal(self):
        return jnp.zeros(6) if self.added_mass is None else jnp.diag(self.added_mass)

    def kinetic_energy(self, v6):
        return 0.0 if self.added_mass is None else 0.5 * v6 @ (self.added_mass @ v6)


# --------------------------------------------------------------------------------------------
# Radiation fit (host)


class RadiationFit(NamedTuple):
    """The fitted memory on the host: per state k, pole p[k] (complex), input dof inp[k], output
    coefficients c[:, k] (6, complex); A_inf (6, 6); and the fit's relative error per column."""
    p: np.ndarray
    inp: np.ndarray
    c: np.ndarray
    added_mass_infinite: np.ndarray
    error: np.ndarray      # (6,) max |K_fit - K| / max |K| over the table, per column (0 for a column without memory)

    def kernel_frequency(self, omega):
        """K(iw) of the fit (n, 6, 6): sum_k c_ik / (i w - p_k) (both conjugates of a complex pole)."""
        s = 1j * np.asarray(omega, dtype=float)[:, None]
        out = np.zeros((s.shape[0], 6, 6), dtype=complex)
        for j in range(6):
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
        out = np.zeros((t.size, 6, 6))
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


def fit_radiation(omega, added_mass, damping, added_mass_infinite=None, order: int = 0, tol: float = 0.005,
                  max_pairs: int = 12, threshold: float = 1e-2):
    """Fit the memory to tables A(w), B(w) (n, 6, 6) about the COG; returns a RadiationFit.

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
    poles, inps, cs = [], [], []
    err = np.zeros(6)
    for i in range(6):
        for j in range(i, 6):
            ref = np.sqrt(dsize[i] * dsize[j])
            if ref <= 0 or size[i, j] <= threshold * ref:
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
                    c = np.zeros(6, dtype=complex)
                    c[out] = r[0, k] if p[k].imag == 0 else 2.0 * r[0, k]   # a pair: Re(2 r e^{pt})
                    poles.append(p[k])
                    inps.append(inp)
                    cs.append(c)
    c = np.array(cs).T if cs else np.zeros((6, 0), dtype=complex)
    return RadiationFit(np.array(poles, dtype=complex), np.array(inps, dtype=int), c, Ainf, err)


def memory_module(fit: RadiationFit) -> Optional[Memory]:
    if fit.p.size == 0:
        return None
    sel = np.zeros((fit.p.size, 6))
    sel[np.arange(fit.p.size), fit.inp] = 1.0
    return Memory(jnp.asarray(fit.p.real), jnp.asarray(fit.p.imag), jnp.asarray(sel),
                  jnp.asarray(fit.c.real), jnp.asarray(fit.c.imag))


# --------------------------------------------------------------------------------------------
# Frequency-domain response (host): the reference of the tests and the notebook


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


# --------------------------------------------------------------------------------------------
# Tables of a scene (host)


class Tables(NamedTuple):
    """Hydrodynamic tables about the COG: frequencies (n,), added mass and damping (n, 6, 6),
    A_inf (6, 6) or None, headings (h,), excitation X (n, h, 6) complex (our convention, see
    waves.py) or None."""
    omega: np.ndarray
    added_mass: Optional[np.ndarray]
    damping: Optional[np.ndarray]
    added_mass_infinite: Optional[np.ndarray]
    headings: Optional[np.ndarray]
    excitation: Optional[np.ndarray]


def _full(x, n):
    """A table given per frequency as 6 values (diagonal) or 6 x 6 -> (n, 6, 6)."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 2:
        out = np.zeros((n, 6, 6))
        out[:, range(6), range(6)] = a
        return out
    return a


def _matrix6(x):
    a = np.asarray(x, dtype=float)
    return np.diag(a) if a.ndim == 1 else a


def scene_tables(hd, hull=None, environment=None, waves=None) -> Tables:
    """The tables of a `[vessel.hydrodynamics]` (scene_types.Hydrodynamics): as written, or from
    Capytaine when `capytaine = true` (cached per hull, frequencies, headings and environment)."""
    if hd.capytaine:
        heading = None if waves is None else waves.heading
        depth = None if waves is None else waves.depth
        freqs = tuple(hd.frequencies) if hd.frequencies else None
        return capytaine_tables(hull, environment.water_density, environment.gravity, depth, freqs,
                                () if heading is None else (float(heading),), hd.panel_size)
    n = len(hd.frequencies)
    w = np.asarray(hd.frequencies, dtype=float)
    A = _full(hd.added_mass, n) if hd.added_mass is not None else None
    B = _full(hd.damping, n) if hd.damping is not None else None
    Ainf = _matrix6(hd.added_mass_infinite) if hd.added_mass_infinite is not None else None
    X = None
    heads = None
    if hd.excitation_amplitude is not None:
        amp = np.asarray(hd.excitation_amplitude, dtype=float)
        ph = np.asarray(hd.excitation_phase, dtype=float)
        if amp.ndim == 2:
            amp, ph = amp[:, None, :], ph[:, None, :]
        X = amp * np.exp(1j * ph)
        heads = np.atleast_1d(np.asarray(hd.headings, dtype=float))
    return Tables(w, A, B, Ainf, heads, X)


def interpolate_excitation(tables: Tables, omega, heading):
    """X (N, 6) at the components' frequencies and the wave heading: linear in w and in heading on
    the complex values; zero outside the tabulated frequencies."""
    w = np.asarray(omega, dtype=float)
    X = tables.excitation
    heads = tables.headings
    if heads.size == 1:
        Xh = X[:, 0, :]
    else:
        Xh = np.zeros((X.shape[0], 6), dtype=complex)
        for j in range(6):
            for i in range(X.shape[0]):
                Xh[i, j] = np.interp(heading, heads, X[i, :, j].real) + 1j * np.interp(heading, heads, X[i, :, j].imag)
    out = np.zeros((w.size, 6), dtype=complex)
    inside = (w >= tables.omega[0] - 1e-12) & (w <= tables.omega[-1] + 1e-12)
    for j in range(6):
        out[:, j] = (np.interp(w, tables.omega, Xh[:, j].real) + 1j * np.interp(w, tables.omega, Xh[:, j].imag))
    return out * inside[:, None]


# --------------------------------------------------------------------------------------------
# Capytaine (optional: pip install jaxslosh[hydro])


CAPYTAINE_MISSING = "needs Capytaine, an optional extra: pip install 'jaxslosh[hydro]' (or pip install capytaine)"


def have_capytaine() -> bool:
    import importlib.util
    try:
        return importlib.util.find_spec("capytaine") is not None
    except (ImportError, ValueError):
        return False


def _import_capytaine():
    try:
        import capytaine as cpt
    except ImportError as e:
        raise ImportError(CAPYTAINE_MISSING) from e
    import logging
    logging.getLogger("capytaine").setLevel(logging.ERROR)
    return cpt


def default_frequencies(n: int = 40, lo: float = 0.1, hi: float = 4.0):
    return tuple(np.linspace(lo, hi, n))


def _box_body(cpt, hull, panel_size, resolution=None, lid=True):
    """The wetted part of a box hull (the COG at the origin), with a lid on the waterplane against
    irregular frequencies, and the six rigid dofs about the COG."""
    L, B, T, kg = hull.length, hull.beam, hull.draft, hull.kg
    size = panel_size or max(min(L, B, T) / 4.0, max(L, B) / 24.0)
    res = resolution or tuple(max(2, int(np.ceil(x / size))) for x in (L, B, 2 * T))
    z_wl = T - kg
    mesh = cpt.mesh_parallelepiped(size=(L, B, 2 * T), center=(0.0, 0.0, z_wl), resolution=res, name="hull")
    return _body_from_mesh(cpt, mesh, z_wl, lid)


def _body_from_mesh(cpt, mesh, z_wl, lid=True):
    # Capytaine puts the free surface at z = 0: the mesh goes down by the waterline height; the COG
    # (our origin) then sits at z = -z_wl.
    mesh = mesh.translated((0.0, 0.0, -z_wl))
    hull = mesh.immersed_part()
    cog = (0.0, 0.0, -z_wl)
    try:
        if not lid:
            raise TypeError
        lid = hull.generate_lid(z=-1e-3 * max(1.0, abs(z_wl)))
        body = cpt.FloatingBody(mesh=hull, lid_mesh=lid, dofs=cpt.rigid_body_dofs(rotation_center=cog),
                                center_of_mass=cog, name="hull")
    except (AttributeError, TypeError):    # Capytaine without lids
        body = cpt.FloatingBody(mesh=hull, dofs=cpt.rigid_body_dofs(rotation_center=cog), center_of_mass=cog,
                                name="hull")
    return body


def _mesh_body(cpt, hull, base_dir=""):
    import os
    path = hull.file if os.path.isabs(hull.file) or not base_dir else os.path.join(base_dir, hull.file)
    mesh = cpt.load_mesh(path)
    # the mesh's coordinates: waterline at z = 0; our origin is the COG at `cog`
    mesh = mesh.translated(tuple(-np.asarray(hull.cog)))
    return _body_from_mesh(cpt, mesh, -float(hull.cog[2]))


def capytaine_hydrostatics(hull, rho=1025.0, g=9.81, panel_size=None, base_dir=""):
    """Hydrostatics of a hull from Capytaine: displaced volume, waterplane area, BM_T, BM_L, KB
    (the centre of buoyancy's height above the keel for a box), GM_T and GM_L about the COG."""
    cpt = _import_capytaine()
    if hull.type == "box":
        # Capytaine integrates the waterplane's second moments at panel centres: with n panels across,
        # BM is low by 1/n^2, so hydrostatics (cheap: no BEM) take 40 along and across (BM -0.06 %)
        res = None if panel_size else (40, 40, 4)
        body = _box_body(cpt, hull, panel_size, resolution=res, lid=False)
    else:
        body = _mesh_body(cpt, hull, base_dir)
    V = float(body.disp_volume)
    zb = float(body.center_of_buoyancy[2])
    zg = float(body.center_of_mass[2])
    bmt = float(body.transversal_metacentric_radius)
    bml = float(body.longitudinal_metacentric_radius)
    return {"displaced_volume": V, "waterplane_area": float(body.waterplane_area), "bm_t": bmt, "bm_l": bml,
            "gm_t": bmt + zb - zg, "gm_l": bml + zb - zg, "z_b": zb - zg}


@functools.lru_cache(maxsize=16)
def _capytaine_cached(hull, rho, g, depth, frequencies, headings, panel_size, base_dir):
    cpt = _import_capytaine()
    body = _box_body(cpt, hull, panel_size) if hull.type == "box" else _mesh_body(cpt, hull, base_dir)
    w = np.asarray(frequencies if frequencies else default_frequencies(), dtype=float)
    kw = {"rho": rho, "g": g}
    if depth is not None:
        kw["water_depth"] = depth
    solver = cpt.BEMSolver()
    dofs = list(body.dofs)
    probs = [cpt.RadiationProblem(body=body, radiating_dof=d, omega=float(x), **kw) for d in dofs for x in w]
    probs += [cpt.DiffractionProblem(body=body, wave_direction=float(b), omega=float(x), **kw)
              for b in headings for x in w]
    results = solver.solve_all(probs, progress_bar=False) if _accepts(solver.solve_all, "progress_bar") \
        else solver.solve_all(probs)
    ds = cpt.assemble_dataset(results)
    order = [d for d in dofs]
    A = ds["added_mass"].sel(omega=w, radiating_dof=order, influenced_dof=order).transpose(
        "omega", "influenced_dof", "radiating_dof").values
    B = ds["radiation_damping"].sel(omega=w, radiating_dof=order, influenced_dof=order).transpose(
        "omega", "influenced_dof", "radiating_dof").values
    try:
        inf = [solver.solve(cpt.RadiationProblem(body=body, radiating_dof=d, omega=np.inf, **kw)) for d in dofs]
        Ainf = np.array([[r.added_masses[i] for r in inf] for i in order])
    except Exception:   # noqa: BLE001 - an older Capytaine without infinite frequency: fitted instead
        Ainf = None
    X = heads = None
    if headings:
        F = ds["excitation_force"].sel(omega=w, influenced_dof=order).transpose("omega", "wave_direction",
                                                                                 "influenced_dof").values
        X = np.conj(F)            # Capytaine's e^{-i w t} convention -> ours (waves.py)
        heads = np.asarray(ds["wave_direction"].values, dtype=float)
    return Tables(w, A, B, Ainf, heads, X)


def _accepts(fn, name):
    import inspect
    try:
        return name in inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return False


def capytaine_tables(hull, rho=1025.0, g=9.81, depth=None, frequencies=None, headings=(), panel_size=None,
                     base_dir="") -> Tables:
    """Added mass, damping (n, 6, 6), A_inf and excitation (FK + diffraction) for the headings, from a
    Capytaine BEM solve of the hull's wetted surface (with a lid against irregular frequencies),
    about the COG. Cached: one solve per hull and settings in a process."""
    return _capytaine_cached(hull, float(rho), float(g), None if depth is None else float(depth),
                             tuple(float(x) for x in frequencies) if frequencies else None,
                             tuple(float(x) for x in headings), panel_size, base_dir)


def hull_hydrodynamics(hull, *, rho=1025.0, g=9.81, depth=None, frequencies=None, headings=(0.0,),
                       panel_size=None, base_dir=""):
    """Hydrostatics and hydrodynamic tables of a hull (scene_types.Hull) from Capytaine, as a dict
    in the form of a scene's `[vessel.hydrostatics]` and `[vessel.hydrodynamics]` tables (see
    `to_toml`): the way to feed a scene without Capytaine at run time."""
    hs = capytaine_hydrostatics(hull, rho, g, None, base_dir)     # its own fine mesh (no BEM)
    t = capytaine_tables(hull, rho, g, depth, frequencies, headings, panel_size, base_dir)
    hydro = {"frequencies": t.omega.tolist(), "added_mass": t.added_mass.tolist(), "damping": t.damping.tolist()}
    if t.added_mass_infinite is not None:
        hydro["added_mass_infinite"] = t.added_mass_infinite.tolist()
    if t.excitation is not None:
        hydro["headings"] = t.headings.tolist()
        hydro["excitation_amplitude"] = np.abs(t.excitation).tolist()
        hydro["excitation_phase"] = np.angle(t.excitation).tolist()
    return {"hydrostatics": {k: hs[k] for k in ("waterplane_area", "displaced_volume", "gm_t", "gm_l")},
            "hydrodynamics": hydro, "bm_t": hs["bm_t"], "bm_l": hs["bm_l"]}


def _toml_value(x, digits=10):
    if isinstance(x, (list, tuple)):
        if x and isinstance(x[0], (list, tuple)):
            return "[\n" + ",\n".join("  " + _toml_value(r, digits) for r in x) + ",\n]"
        return "[" + ", ".join(_toml_value(v, digits) for v in x) + "]"
    v = float(x)
    if v == 0.0:
        return "0.0"
    return f"{v:.{digits}g}" if ("e" in f"{v:.{digits}g}" or "." in f"{v:.{digits}g}") else f"{v:.{digits}g}.0"


def to_toml(data: dict) -> str:
    """The `[vessel.hydrostatics]` and `[vessel.hydrodynamics]` tables of `hull_hydrodynamics` as TOML."""
    lines = ["[vessel.hydrostatics]"]
    lines += [f"{k} = {_toml_value(v)}" for k, v in data["hydrostatics"].items()]
    lines += ["", "[vessel.hydrodynamics]"]
    for k, v in data["hydrodynamics"].items():
        if k in ("excitation_amplitude", "excitation_phase"):
            v = [[list(map(float, h)) for h in f] for f in v]
        lines.append(f"{k} = {_toml_value(v)}")
    return "\n".join(lines) + "\n"


__all__ = ["CAPYTAINE_MISSING", "Memory", "RadiationFit", "Seakeeping", "Tables", "capytaine_hydrostatics",
           "capytaine_tables", "fit_radiation", "have_capytaine", "hull_hydrodynamics", "interpolate_excitation",
           "linear_response", "memory_module", "restoring_matrix", "rigid_mass_matrix", "scene_tables", "to_toml",
           "vector_fit", "DOFS"]


# --------------------------------------------------------------------------------------------
# From a scene to the traced Seakeeping (build.py calls this)


def excitation_source(scene) -> Optional[str]:
    """"table" or "froude-krylov": where the wave forces of a scene come from (None without waves)."""
    if scene.waves is None:
        return None
    hd = scene.vessel.hydrodynamics
    tables = hd is not None and (hd.capytaine or hd.excitation_amplitude is not None)
    if hd is not None and hd.excitation != "auto":
        return hd.excitation
    return "table" if tables else "froude-krylov"


def _tables_of(scene) -> Tables:
    env, ves, waves = scene.environment, scene.vessel, scene.waves
    hd = ves.hydrodynamics
    if hd.capytaine:
        heads = () if waves is None else (float(waves.heading),)
        return capytaine_tables(ves.hull, env.water_density, env.gravity, None if waves is None else waves.depth,
                                hd.frequencies or None, heads, hd.panel_size, hd.base_dir)
    return scene_tables(hd)


@functools.lru_cache(maxsize=32)
def _radiation_fit_cached(hd, hull, rho, g, depth, heading):
    class _S:   # the parts of a scene that _tables_of reads
        pass
    s = _S()
    s.environment = type("E", (), {"water_density": rho, "gravity": g})()
    s.vessel = type("V", (), {"hydrodynamics": hd, "hull": hull})()
    s.waves = None if heading is None else type("W", (), {"heading": heading, "depth": depth})()
    t = _tables_of(s)
    return fit_radiation(t.omega, t.added_mass, t.damping, t.added_mass_infinite, order=hd.memory_order)


def radiation_fit(scene) -> Optional[RadiationFit]:
    """The memory fit of a scene's hydrodynamic tables (cached), or None without added mass and damping."""
    hd = scene.vessel.hydrodynamics
    if hd is None or not (hd.capytaine or hd.added_mass is not None):
        return None
    w = scene.waves
    return _radiation_fit_cached(hd, scene.vessel.hull, scene.environment.water_density, scene.environment.gravity,
                                 None if w is None else w.depth, None if w is None or not hd.capytaine else w.heading)


def excitation_rao(scene, omega):
    """X (N, 6) complex: the scene's wave forces per unit amplitude at frequencies omega, for its
    wave heading, from its source (tables or Froude-Krylov on the box hull)."""
    from .waves import froude_krylov_box
    waves, ves, env = scene.waves, scene.vessel, scene.environment
    if excitation_source(scene) == "table":
        return interpolate_excitation(_tables_of(scene), omega, waves.heading)
    h = ves.hull
    return froude_krylov_box(omega, waves.heading, h.length, h.beam, h.draft, h.kg, env.water_density,
                             env.gravity, waves.depth)


def build_seakeeping(scene, params: dict) -> Optional[Seakeeping]:
    """The Seakeeping of a scene with what its effects switch on; None when nothing is left.
    Host-side tables use the scene's water density and gravity (params overrides of those do not
    reach the hydrodynamic coefficients); `waves.amplitude` / `waves.hs` may be traced."""
    from .waves import make_excitation, components
    eff, ves, waves = scene.effects, scene.vessel, scene.waves
    excitation = None
    if waves is not None and eff.waves:
        key = "waves.amplitude" if waves.type == "regular" else "waves.hs"
        X = excitation_rao(scene, components(waves).omega)
        excitation = make_excitation(waves, X, params.get(key, waves.height))
    added_mass = damping = memory = None
    hd = ves.hydrodynamics
    if hd is not None and eff.radiation:
        fit = radiation_fit(scene)
        if fit is not None:
            added_mass = jnp.asarray(fit.added_mass_infinite)
            memory = memory_module(fit)
        if hd.viscous_damping is not None:
            damping = jnp.asarray(_matrix6(hd.viscous_damping))
    if excitation is None and added_mass is None and damping is None:
        return None
    return Seakeeping(excitation=excitation, added_mass=added_mass, damping=damping, memory=memory)
