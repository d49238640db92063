"""The liquid element: energies of each term, and their Hessians (the element matrices).

Element forms (``ELEMENT_FORMS``)
---------------------------------
``"paper"`` -- the literal eqs. (30)-(31): mean dilatation plus ``int p0 grad(phi)^T grad(phi) dV``
(full 2x2x2 Gauss), with the gauge pressure ``p0 = rho g (h - z)`` (docs/theory.md items 1-2) and a
consistent mass. The literal term equals the consistent pre-stress energy (which, by parts, is the
free-surface energy ``1/2 rho g int_FS u_z^2``) plus ``p0 (div u)^2 + p0 |curl u|^2``: a rotation
penalty that vanishes at the free surface. Known defects (measured, see tests): a circulation mode
at 2.90 rad/s inside the sloshing band of the 5x5x3 m tank on the 5x5x5 mesh, sloshing frequencies
1.5-4.5 % high on that mesh, and a free surface that does not stay level under a static tilt
(its P0 pressure does not match the nodal free surface at the walls: 11 % on 5x5x5).

``"stabilized"`` (default) -- built so that the discrete hydrostatics is exact and no spurious mode
enters the sloshing band. Its stiffness is the sum of

1. acoustic: mean dilatation, eq. (30) (one pressure per element, "P0");
2. free surface: the by-parts form of the consistent pre-stress with the gauge p0 (docs/theory.md
   item 3): ``1/2 rho g sum_faces A (mean u_z)^2`` -- the gravity energy of the volume each top
   face displaces -- plus the small volume coupling ``-rho g int u_z (mean div u)``. The face mean
   (rather than the nodal field) is what matches the P0 pressure: for a linear pressure the balance
   of every surface node is then exact, so under a static tilt the free surface stays level;
3. rotation penalty ``1/2 kappa int |P curl d + 2 theta|^2 dV``: P projects each component curl_k
   onto span{1, x_k} inside the element (two Gauss points along axis k, one across). With the
   one-point divergence this is a "box scheme" for the discrete potential flow: every circulation
   mode is held far above the sloshing band (kappa = 10 rho g L, L the largest tank dimension; the
   lowest circulation mode is then about 6x the lowest sloshing one) and the sloshing modes do not
   lock (on 5x5x5 they move by < 0.05 % between kappa = 5e4 and 2e6 Pa). Along a row with an odd
   number n > 1 of elements the box scheme cannot close a uniform surface slope at both walls (an
   alternating-sum condition; the nodal surface of a tilt would carry a zig-zag of relative size
   1/n^2), so in the top layer the two wall elements of each such row are penalised on the
   difference of their curls only (see ``_rotation_penalty``). ``theta`` is the small body rotation
   (docs/theory.md item 5): ``stiffness`` holds the d-d block, ``rotation_coupling`` the d-theta block
   and ``rotation_stiffness`` the theta-theta block;
4. surface hourglass control that is zero on every linear surface field (so tilts stay exact):
   ``1/2 rho g A (h.u_z/4)^2`` per top face (h = (1,-1,1,-1)), and a weak surface "bending"
   ``1/2 eps rho g sum_nodes A (second difference of u_z)^2`` (eps = 0.025) against the zig-zag
   surface patterns that no element-local term can see.

Its mass is the kinetic energy ``1/2 rho int |v|^2`` integrated with 8 points at
``(+-xi_h, +-xi_h, +-xi_z)`` instead of Gauss' 1/sqrt(3). Any such rule keeps the total mass, the
centre of mass and the load ``kron(mass, I3) tile(g)`` (every column sum is the lumped nodal mass);
the spread is chosen to cancel the box scheme's O(h^2) dispersion: vertically, the mid-point
kinetic energy (xi_z -> 0) makes the discrete decay of a deep-water mode exact to O(h^2);
horizontally, the consistent mass is exact to O(h^2) for waves along an axis and a slightly narrower
rule balances diagonal ones. xi_z = 0.183 (0.9 of the way to mid-point, to keep M well conditioned,
cond ~ 600) and xi_h = 0.548 are calibrated on the 5x5x5, 10x10x6 and slab meshes (first four
distinct sloshing frequencies within 1.4 %, 0.42 % and 0.3 %). Side effect: second moments of this
mass (the frozen inertia R^T M R) are low by 2 beta (h_e/L)^2 (z^2: -3.6 %, x^2: -0.4 %, I_xx:
-1.2 % on 5x5x5; -0.7 % on 10x10x6).

Limits: a direction meshed with a single element carries no sloshing along it (its one-element
curl constraint holds the surface flat that way: a static tilt along it is not followed at all);
use >= 2 elements along every direction in which the surface should move.
"""
from __future__ import annotations


import jax
import jax.numpy as jnp
import numpy as np

from ...staging import XLA_OPTIONS, lower_program, no_eager_folding
from ...fem.linalg import det2, det3, inv3
from ...fem.mesh import GAUSS8, GAUSS_1D, HEX_CORNERS

#: kappa = ROTATION_PENALTY * rho * g * max(a, b, h): kappa k^2 / rho >= 10 pi g k / L puts every circulation
#: mode well above the gravity waves of the same wavenumber (5x5x3 m tank, 5x5x5: first at 6.2x the first sloshing).
ROTATION_PENALTY = 10.0

#: stiffness of the 2D checkerboard of a top face relative to a uniform raise of that face.
SURFACE_HOURGLASS = 1.0

#: weight of the surface second-difference ("bending") term relative to the free-surface stiffness.
SURFACE_BENDING = 0.025

#: the divergence's variation inside an element, penalised where a mapped mesh has an element with
#: two faces on one smooth wall (fem/slip.py): 1/2 eps kappa int (div u - mean div u)^2 dV (2x2x2
#: Gauss). Such an element (a disk meshed from a square: a corner of the square on the circle) has an
#: angle near 180 degrees there, and the node at it slides along the wall with no energy of the
#: one-point divergence or the axial curl; this term holds it. Only those elements get it: sloshing
#: fields carry a divergence variation at the mesh's resolution, which it would stiffen everywhere.
FLAT_CORNER_PENALTY = 1.0

#: 1D kinetic-energy quadrature points +-xi for the stabilized mass (consistent: 1/sqrt(3)).
#: xi = sqrt(1 - 4 b) for the 1D off-diagonal mass b; b = (1 - beta)/6 with beta the blend towards
#: lumped (beta < 0: towards the mid-point rule). Horizontal beta = -0.05, vertical beta = -0.45.
MASS_XI_HORIZONTAL = float(np.sqrt(1.0 - 4.0 * (1.0 + 0.05) / 6.0))

MASS_XI_VERTICAL = float(np.sqrt(1.0 - 4.0 * (1.0 + 0.45) / 6.0))

_FACE_HOURGLASS = np.array([1.0, -1.0, 1.0, -1.0])


def is_traced(x) -> bool:
    return isinstance(x, jax.core.Tracer)

_CHUNK = 128          # elements per jitted batch: fixed shapes, so each kernel compiles once per process


def element_matrices(xe, xf, rho, c, g, h, form, with_parts=True, div_variation=False):
    """Element matrices of every term (Hessians of the energies below): NumPy arrays for concrete
    values, JAX arrays when any input is traced.

    ``xe``/``xf`` NumPy or JAX; ``rho, c, g, h`` floats or tracers. Without ``with_parts`` the
    kernels needed only for the mode-classification measures ("paper": the consistent free surface
    and the p0 |curl|^2 part) are skipped."""

    with jax.enable_x64(True):
        xi_h, xi_z = (GAUSS_1D, GAUSS_1D) if form == "paper" else (MASS_XI_HORIZONTAL, MASS_XI_VERTICAL)
        if any(is_traced(v) for v in (rho, c, g, h)):
            prm = jnp.stack([jnp.asarray(v, dtype=jnp.float64) for v in (rho, c, g, h, 0.0, xi_h, xi_z)])
        else:
            prm = jnp.array([rho, c, g, h, 0.0, xi_h, xi_z], dtype=jnp.float64)
        traced_x = is_traced(xe) or is_traced(prm)
        kern = {name: k for name, k in _kernels(form).items()
                if (with_parts or form != "paper" or name not in ("free_surface", "rotation"))
                and (name != "div_variation" or div_variation)}
        out = {}
        if not traced_x:              # concrete: chunks cut and joined in NumPy (no eager JAX op to compile)
            # every energy is invariant under horizontal shifts (p0 depends on z only), so each
            # distinct element shape and height is computed once (a uniform grid: one per layer)
            distinct = {name: _distinct(np.asarray(xf if on_faces else xe, dtype=np.float64),
                                        horizontal_only=not on_faces) for name, (_, on_faces) in kern.items()}
            chunks = {name: [_padded(x[i:i + _CHUNK]) for i in range(0, len(x), _CHUNK)]
                      for name, (x, _) in distinct.items()}
            for name, (fn, _) in kern.items():     # every kernel traced, XLA compiling them meanwhile
                fn.lower(prm, chunks[name][0][0])
            for name, (fn, _) in kern.items():
                blocks = [np.asarray(fn(prm, chunk, concrete=True))[:keep] for chunk, keep in chunks[name]]
                out[name] = np.concatenate(blocks)[distinct[name][1]]
            return out
        for name, (fn, on_faces) in kern.items():   # traced: the same fixed-shape chunks, cut by dynamic slices
            x = jnp.asarray(xf if on_faces else xe, dtype=jnp.float64)
            n = len(x)
            pad = -n % _CHUNK
            xpad = jnp.concatenate([x, jnp.repeat(x[:1], pad, axis=0)]) if pad else x
            blocks = [fn(prm, jax.lax.dynamic_slice_in_dim(xpad, i, _CHUNK)) for i in range(0, n, _CHUNK)]
            out[name] = (blocks[0] if len(blocks) == 1 else jnp.concatenate(blocks))[:n]
    return out


def _padded(chunk):
    """(a chunk of at most _CHUNK elements padded to _CHUNK with copies of its first, its length)."""
    pad = _CHUNK - len(chunk)
    if pad:
        chunk = np.concatenate([chunk, np.repeat(chunk[:1], pad, axis=0)])
    return jnp.asarray(chunk, dtype=jnp.float64), _CHUNK - pad


def _distinct(x, horizontal_only):
    """(the distinct elements of x (n, k, dim) up to a shift of their first corner, index of each
    element's representative): horizontal shifts for volume elements, any shift for surface faces."""
    rel = x.copy()
    dims = slice(0, 2) if horizontal_only else slice(None)
    rel[:, :, dims] -= x[:, :1, dims]
    scale = max(float(np.abs(x).max()), 1e-300)
    key = np.round(rel.reshape(len(x), -1) / scale, 11)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return x[first], inverse.reshape(-1)

_KERNEL_CACHE: dict = {}


def _kernel_compiler_options():
    """XLA's cheapest CPU codegen (no LLVM optimisation, the classic loop emitters) for the kernels,
    which run once per build; None elsewhere (the options are the CPU backend's)."""
    if jax.default_backend() != "cpu":
        return None
    return {"xla_backend_optimization_level": 0, **XLA_OPTIONS}


def _kernels(form):
    """Jitted, batched Hessians of the element energies of one form: {name: (fn(prm, x), on_faces)}."""
    if form in _KERNEL_CACHE:
        return _KERNEL_CACHE[form]

    with jax.ensure_compile_time_eval(), jax.enable_x64(True):   # concrete constants even if first built under a trace
        XI = jnp.asarray(HEX_CORNERS)
        XI2 = jnp.asarray(HEX_CORNERS[:4, :2])
        gauss = jnp.asarray(GAUSS8)
        gauss4 = jnp.asarray(GAUSS8[::2, :2])
        corners = jnp.asarray(HEX_CORNERS)
        axial = jnp.asarray([[s if k == j else 0.0 for j in range(3)] for k in range(3) for s in (-GAUSS_1D, GAUSS_1D)])
        axial_comp = jnp.asarray([0, 0, 1, 1, 2, 2])

    def at(x, xi):
        """Shape values (8,), physical gradients (8, 3) and det J of the hex at reference point xi."""
        N = jnp.prod(1.0 + XI * xi, axis=1) / 8.0
        dN = jnp.stack([XI[:, k] * jnp.prod(jnp.where(jnp.arange(3) == k, 1.0, 1.0 + XI * xi), axis=1)
                        for k in range(3)], axis=1) / 8.0
        J = x.T @ dN
        return N, dN @ inv3(J), det3(J)                 # closed forms: no LAPACK (fem/linalg.py)

    def points(x, pts):
        return jax.vmap(at, in_axes=(None, 0))(x, pts)

    def grads(d, dNx):                                      # (P, 3, 3): u_i,k at each point
        return jnp.einsum("pak,ai->pik", dNx, d.reshape(8, 3))

    def curls(G):
        return jnp.stack([G[:, 2, 1] - G[:, 1, 2], G[:, 0, 2] - G[:, 2, 0], G[:, 1, 0] - G[:, 0, 1]], axis=1)

    def p0(prm, x, N):                                      # gauge hydrostatic pressure (traps 1-2)
        rho, g, h = prm[0], prm[2], prm[3]
        return rho * g * (h - N @ x[:, 2])

    def e_acoustic(d, prm, x):                              # eq. (30): rho c^2 (int div)^2 / (2 V)
        N, dNx, dJ = points(x, gauss)
        div = jnp.sum(jnp.trace(grads(d, dNx), axis1=1, axis2=2) * dJ)
        return 0.5 * prm[0] * prm[1] ** 2 * div**2 / jnp.sum(dJ)

    def e_coupling(d, prm, x):                              # -rho g int u_z (mean div)   (trap 3)
        N, dNx, dJ = points(x, gauss)
        div = jnp.sum(jnp.trace(grads(d, dNx), axis1=1, axis2=2) * dJ) / jnp.sum(dJ)
        uz = jnp.sum((N @ d.reshape(8, 3)[:, 2]) * dJ)
        return -prm[0] * prm[2] * div * uz

    def e_prestress_paper(d, prm, x):                       # eq. (31) literally: 1/2 int p0 |grad u|^2
        N, dNx, dJ = points(x, gauss)
        G = grads(d, dNx)
        return 0.5 * jnp.sum(p0(prm, x, N) * jnp.sum(G * G, axis=(1, 2)) * dJ)

    def e_rotation_paper(dt, prm, x):                       # the p0 |curl u + 2 theta|^2 part of eq. (31)
        d, theta = dt[:24], dt[24:]
        N, dNx, dJ = points(x, gauss)
        w = curls(grads(d, dNx)) + 2.0 * theta
        return 0.5 * jnp.sum(p0(prm, x, N) * jnp.sum(w * w, axis=1) * dJ)

    def axial_curl(d, prm, x):                              # curl_k d at xi_k = -+1/sqrt(3): P curl d
        N, dNx, dJ = points(x, axial)
        return curls(grads(d, dNx))[jnp.arange(6), axial_comp]

    def volume(prm, x):
        return jnp.sum(points(x, gauss)[2])

    def e_div_variation(d, prm, x):                         # 1/2 int (div u - mean div u)^2
        _, dNx, dJ = points(x, gauss)
        div = jnp.trace(grads(d, dNx), axis1=1, axis2=2)
        mean = jnp.sum(div * dJ) / jnp.sum(dJ)
        return 0.5 * jnp.sum((div - mean) ** 2 * dJ)

    def e_kinetic(v, prm, x):                               # 1/2 rho int v^2, scalar field, spread rule
        pts = corners * jnp.array([prm[5], prm[5], prm[6]])
        N, dNx, dJ = points(x, pts)
        return 0.5 * prm[0] * jnp.sum((N @ v) ** 2 * dJ)

    def face_at(y, xi):
        N = jnp.prod(1.0 + XI2 * xi, axis=1) / 4.0
        dN = jnp.stack([XI2[:, 0] * (1 + XI2[:, 1] * xi[1]), XI2[:, 1] * (1 + XI2[:, 0] * xi[0])], 1) / 4.0
        return N, det2(y.T @ dN)

    def e_surface_consistent(uz, prm, y):                   # 1/2 rho g int_FS u_z^2 (2x2 Gauss)
        N, dJ = jax.vmap(face_at, in_axes=(None, 0))(y, gauss4)
        return 0.5 * prm[0] * prm[2] * jnp.sum((N @ uz) ** 2 * dJ)

    def e_surface_mean(uz, prm, y):                         # 1/2 rho g A (mean u_z)^2
        A = 4.0 * face_at(y, jnp.zeros(2))[1]
        return 0.5 * prm[0] * prm[2] * A * jnp.mean(uz) ** 2

    def e_surface_hourglass(uz, prm, y):                    # 1/2 rho g A (h . u_z / 4)^2, zero on linear fields
        A = 4.0 * face_at(y, jnp.zeros(2))[1]
        return 0.5 * SURFACE_HOURGLASS * prm[0] * prm[2] * A * (jnp.asarray(_FACE_HOURGLASS) @ uz / 4.0) ** 2

    def jit(f, name):
        """The jitted kernel for traced calls; for concrete ones (`concrete=True`) compiled ahead of
        time, once per shape, with the cheapest CPU codegen (the kernels run once per build on a few
        chunks) and traced as a staged program even under `jax.ensure_compile_time_eval()`, where
        run/simulate.py prepare builds: there every constant operation of a jit trace would run
        eagerly, op by op, each compiling a tiny XLA program of its own. A compiled kernel runs
        eagerly even under a user's outer jit; the element matrices are the same bit for bit."""
        out = jax.jit(f)
        compiled = {}

        def lower(prm, x):
            """Traced (or read from the exported programs where a process compiled it before) and
            compiling in the background, once per shape."""
            key = (x.shape, str(x.dtype), prm.shape)
            if key not in compiled:
                with no_eager_folding():
                    compiled[key] = lower_program(f"element-{form}-{name}", f, (prm, x),
                                                  _kernel_compiler_options()).compile_in_background()
            return compiled[key]

        def call(prm, x, concrete=False):
            if not concrete:
                return out(prm, x)
            return lower(prm, x).result()(prm, x)
        call.lower = lower
        return call

    def batched(fn, size, derivative=jax.hessian):
        H = derivative(fn)
        return jit(jax.vmap(lambda prm, x: H(jnp.zeros(size, dtype=x.dtype), prm, x), in_axes=(None, 0)), fn.__name__)

    kern = {
        "mass": (batched(e_kinetic, 8), False),
        "acoustic": (batched(e_acoustic, 24), False),
    }
    if form == "paper":
        kern["free_surface"] = (batched(e_surface_consistent, 4), True)
        kern["rotation"] = (batched(e_rotation_paper, 27), False)
        kern["prestress"] = (batched(e_prestress_paper, 24), False)
    else:
        kern["free_surface"] = (batched(e_surface_mean, 4), True)
        kern["axial_curl"] = (batched(axial_curl, 24, jax.jacfwd), False)
        kern["volume"] = (jit(jax.vmap(volume, in_axes=(None, 0)), "volume"), False)
        kern["coupling"] = (batched(e_coupling, 24), False)
        kern["surface_hourglass"] = (batched(e_surface_hourglass, 4), True)
        kern["div_variation"] = (batched(e_div_variation, 24), False)
    _KERNEL_CACHE[form] = kern
    return kern
