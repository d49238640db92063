"""Lumped-mass mooring lines (MoorDyn's form; docs/guide/moorings-lumped.md).

A line of unstretched length L is cut into N equal segments of length l = L / N between N + 1
nodes: node 0 is the anchor (fixed), node N the fairlead (prescribed by the body), nodes 1..N-1
move. On the moving nodes:

* axial springs: each segment's tension T = EA ramp(e) + BA de/dt with the strain e = |d| / l - 1
  (d the segment's vector). A segment carries no compression: `ramp` is e above a band of
  +-STRAIN_BAND, 0 below it and the quadratic (e + band)^2 / (4 band) inside (C1, so Newton and
  gradients stay defined); BA is the internal damping (N s per unit strain rate);
* weight: the submerged weight w per metre, w l down on each node;
* inertia: the node's mass m l (m in air per metre) plus the added mass rho pi d^2 / 4 l
  [Ca_n (I - q q^T) + Ca_t q q^T], q the node's tangent (the mean of its two segments'
  directions, as MoorDyn), inverted in closed form (Sherman-Morrison);
* Morison drag on the relative velocity u = U_current - v, split by the tangent:
  1/2 rho Cd_n d l |u_n| u_n + 1/2 rho Cd_t pi d l |u_t| u_t;
* the seabed at z = seabed_z: an upward penalty d l (k_b ramp(p) - c_b dramp(p) v_z) with the
  penetration p = seabed_z - z, smoothed by the same quadratic over +-SEABED_BAND; no friction.

Time integration: the nodes' axial frequency omega_a = 2 (N / L) sqrt(EA / m) (about 100 rad/s for
the OC3-Hywind line with 20 segments) is far above a ship's (0.05-1 rad/s). The line is sub-stepped
inside the body's step with an explicit semi-implicit (symplectic) Euler scheme in a `lax.scan`:
v += dt a(r, v); r += dt v, the fairlead's position and velocity over the step from the cubic
Hermite interpolation of its positions and velocities at t_n and t_{n+1}. Why explicit rather than
implicit: the stable sub-step is dt <= 2 / omega (sqrt(1 + zeta^2) - zeta) (taken with a safety
factor SAFETY), a handful of sub-steps per ship step of 0.05-0.1 s at 20 segments, each a few
vector operations on (N - 1, 3) arrays with no linear solve; an implicit (backward-Euler) step would
need a Newton solve on the 3(N - 1) block-tridiagonal system per ship step and damps the line's
own dynamics (the drag and inertia the lumped model is there to give) at the ship's step. The
symplectic Euler scheme keeps an undamped line's energy bounded (no drift) where explicit RK2 has
a growing mode on the imaginary axis; its first-order error is at the sub-step, far below the
ship's step.

The static shape (`static_shape`) minimises the line's potential energy (elastic + weight + seabed)
over the moving nodes by Levenberg-Marquardt Newton steps on the exact Hessian from an L-shaped
start (the inextensible catenary); it starts a run at rest.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp

#: half-width of the strain band over which a segment's tension goes smoothly to zero (compression)
STRAIN_BAND = 1e-5
#: half-width (m) of the band over which the seabed's contact switches on
SEABED_BAND = 1e-3
#: sub-step = SAFETY times the symplectic Euler's stability limit of the fastest mode
SAFETY = 0.5


def _ramp(x, band):
    """max(x, 0) with the corner replaced by a quadratic over [-band, band] (C1)."""
    inside = (x + band) ** 2 / (4.0 * band)
    return jnp.where(x >= band, x, jnp.where(x <= -band, 0.0, inside))


def _ramp_int(x, band):
    """The antiderivative of `_ramp` (0 below -band): the potential of a ramped spring."""
    inside = (x + band) ** 3 / (12.0 * band)
    return jnp.where(x >= band, 0.5 * x * x + band * band / 6.0, jnp.where(x <= -band, 0.0, inside))


def _step01(x, band):
    """d ramp / dx: 0 below -band, 1 above band, linear between (the contact's damping switch)."""
    return jnp.clip((x + band) / (2.0 * band), 0.0, 1.0)


def _norm(x, axis=-1):
    """|x| with a finite gradient at 0 (a node at rest: drag's |u| u)."""
    return jnp.sqrt(jnp.sum(x * x, axis=axis) + 1e-30)


class LumpedLine(eqx.Module):
    """One line's constants (SI units; the inertial frame's z up). `segments` N and `substep_max`
    (the largest stable sub-step, s) are static."""
    anchor: jax.Array            # (3,) inertial
    length: jax.Array            # unstretched L
    weight: jax.Array            # submerged weight per metre w, N/m
    ea: jax.Array
    diameter: jax.Array
    mass: jax.Array              # kg/m in air
    cd: jax.Array                # (2,) normal, tangential
    ca: jax.Array                # (2,)
    ba: jax.Array                # internal damping, N s (force per unit strain rate)
    seabed_z: jax.Array
    seabed_stiffness: jax.Array  # Pa/m
    seabed_damping: jax.Array    # Pa s/m
    rho: jax.Array
    current: jax.Array           # (3,) uniform current, m/s
    segments: int = eqx.field(static=True, default=20)
    substep_max: float = eqx.field(static=True, default=1e-3)

    @property
    def seg(self):
        return self.length / self.segments

    def substeps(self, h: float) -> int:
        """The number of sub-steps of a step h (static)."""
        return max(1, int(math.ceil(float(h) / self.substep_max - 1e-9)))


def lumped_line(anchor, length, weight, ea, *, segments=20, diameter=0.09, mass=None, cd=(1.6, 0.1),
                ca=(1.0, 0.0), internal_damping=-0.8, seabed_z=-jnp.inf, seabed_stiffness=3.0e6,
                seabed_damping=3.0e5, rho=1025.0, gravity=9.81, current=(0.0, 0.0, 0.0),
                substep=None) -> LumpedLine:
    """A line's constants from the scene's values (concrete numbers: the sub-step is chosen here).
    `mass` (kg/m in air) defaults to weight / g plus the displaced water rho pi d^2 / 4;
    `internal_damping` < 0 is that fraction of a segment's critical axial damping l sqrt(EA m)
    (MoorDyn's BA / -zeta convention); `seabed_z` = -depth (no seabed: -inf). `substep` given (the
    largest stable sub-step of the line with the scene's values): `length`, `weight` and `ea` may be
    traced (params, a sweep's runs), the sub-step being static."""
    area = math.pi * diameter ** 2 / 4.0
    m = weight / gravity + rho * area if mass is None else mass
    if segments < 2:
        raise ValueError("a lumped line needs at least 2 segments")
    if substep is None and m <= 0.0:
        raise ValueError(f"a lumped line's mass per metre must be positive, got {m}")
    seg = length / segments
    ba = -internal_damping * seg * jnp.sqrt(ea * m) if internal_damping < 0 else internal_damping
    f = lambda x: jnp.asarray(x, dtype=float)  # noqa: E731
    if substep is not None:
        return LumpedLine(f(anchor), f(length), f(weight), f(ea), f(diameter), f(m), f(cd), f(ca), f(ba),
                          f(seabed_z), f(seabed_stiffness), f(seabed_damping), f(rho), f(current),
                          int(segments), float(substep))
    ba = float(ba)
    # the fastest modes: the axial one (adjacent nodes out of phase, node mass m l without the
    # tangential added mass, which is 0 by default) and the seabed's vertical spring (with its added
    # mass); their damping ratios from BA and c_b
    m_ax = m + rho * area * ca[1]
    w_ax = 2.0 * math.sqrt(ea / (m_ax * seg * seg))
    # the highest axial mode loads a node with 4 BA / l per unit velocity: zeta = 2 BA / (l^2 m omega)
    # (MoorDyn's -zeta convention gives that mode the damping ratio zeta)
    z_ax = 2.0 * ba / (seg * seg * m_ax * w_ax)
    m_n = m + rho * area * ca[0]
    w_sb = math.sqrt(seabed_stiffness * diameter / m_n) if seabed_z > -math.inf else 0.0
    z_sb = seabed_damping * diameter / (2.0 * m_n * max(w_sb, 1e-30))

    def limit(w, z):
        return math.inf if w == 0.0 else 2.0 / w * (math.sqrt(1.0 + z * z) - z)

    dt = SAFETY * min(limit(w_ax, z_ax), limit(w_sb, z_sb))
    return LumpedLine(f(anchor), f(length), f(weight), f(ea), f(diameter), f(m), f(cd), f(ca), f(ba),
                      f(seabed_z), f(seabed_stiffness), f(seabed_damping), f(rho), f(current),
                      int(segments), float(dt))


class LineState(NamedTuple):
    r: jax.Array    # (N - 1, 3) the moving nodes' positions
    v: jax.Array    # (N - 1, 3) their velocities
    dissipated: jax.Array = 0.0   # J: the work the internal damping, drag and seabed damping took out
    work: jax.Array = 0.0         # J: the work the fairlead did on the line


def _nodes(line: LumpedLine, r, fair):
    return jnp.concatenate([line.anchor[None], r, fair[None]], axis=0)


def _segments(line: LumpedLine, r_all, v_all):
    """(T (N,), unit vectors (N, 3) from node j to j + 1, strain rates (N,)) of the segments."""
    d = r_all[1:] - r_all[:-1]
    ln = _norm(d)
    q = d / ln[:, None]
    l0 = line.seg
    e = ln / l0 - 1.0
    e_dot = jnp.sum(q * (v_all[1:] - v_all[:-1]), axis=-1) / l0
    return line.ea * _ramp(e, STRAIN_BAND) + line.ba * e_dot, q, e_dot


def segment_tensions(line: LumpedLine, r_all, v_all):
    """(T (N,), unit vectors (N, 3) from node j to j + 1) of the segments (nodes (N + 1, 3))."""
    return _segments(line, r_all, v_all)[:2]


def _node_loads(line: LumpedLine, r_all, v_all, power=False):
    """(external loads on every node but the segments' (N + 1, 3): weight, drag, seabed; tangents
    (N + 1, 3), each node's share of the line's length (N + 1,)). The end nodes carry half a
    segment. `power`: the power (W) the drag and the seabed's damping take out of the moving nodes
    too, appended."""
    n = line.segments
    l0 = line.seg
    share = jnp.full((n + 1,), l0).at[0].set(0.5 * l0).at[-1].set(0.5 * l0)
    d = r_all[1:] - r_all[:-1]
    qs = d / _norm(d)[:, None]
    tan = jnp.concatenate([qs[:1], qs[:-1] + qs[1:], qs[-1:]], axis=0)
    tan = tan / _norm(tan)[:, None]
    u = line.current[None] - v_all
    ut = jnp.sum(u * tan, axis=-1, keepdims=True) * tan
    un = u - ut
    half_rho_d = 0.5 * line.rho * line.diameter * share[:, None]
    drag = half_rho_d * (line.cd[0] * _norm(un)[:, None] * un + line.cd[1] * jnp.pi * _norm(ut)[:, None] * ut)
    p = line.seabed_z - r_all[:, 2]
    c_bed = line.diameter * share * line.seabed_damping * _step01(p, SEABED_BAND)
    bed = line.diameter * share * line.seabed_stiffness * _ramp(p, SEABED_BAND) - c_bed * v_all[:, 2]
    bed = jnp.where(jnp.isfinite(line.seabed_z), bed, 0.0)
    fz = bed - line.weight * share
    out = drag.at[:, 2].add(fz), tan, share
    if not power:
        return out
    # the drag's work against the nodes' velocity (negative where a current drives them) and the
    # seabed's damping, c v_z^2: what the moving nodes' equations lose besides the conservative forces
    c_bed = jnp.where(jnp.isfinite(line.seabed_z), c_bed, 0.0)
    lost = -jnp.sum(drag[1:-1] * v_all[1:-1]) + jnp.sum(c_bed[1:-1] * v_all[1:-1, 2] ** 2)
    return out + (lost,)


def _rates(line: LumpedLine, r, v, fair_r, fair_v):
    """(the moving nodes' accelerations (N - 1, 3), the power (W) the internal damping, the drag
    and the seabed's damping take out of the line, the power the fairlead puts into it)."""
    r_all = _nodes(line, r, fair_r)
    v_all = _nodes(line, v, fair_v).at[0].set(0.0)
    T, q, e_dot = _segments(line, r_all, v_all)
    f_seg = T[:, None] * q                    # pulls node j towards j + 1 and j + 1 towards j
    loads, tan, share, lost = _node_loads(line, r_all, v_all, power=True)
    f = (f_seg[1:] - f_seg[:-1] + loads[1:-1])
    t = tan[1:-1]
    vol = jnp.pi * line.diameter ** 2 / 4.0 * line.seg
    alpha = line.mass * line.seg + line.rho * vol * line.ca[0]
    beta = line.rho * vol * (line.ca[1] - line.ca[0])
    tf = jnp.sum(t * f, axis=-1, keepdims=True)
    # each segment's damping force BA e' along it, against its stretching rate l e': BA l e'^2;
    # the fairlead pulls the last segment's end with its whole tension
    lost = lost + line.ba * line.seg * jnp.sum(e_dot * e_dot)
    return (f - beta / (alpha + beta) * tf * t) / alpha, lost, T[-1] * jnp.dot(q[-1], fair_v)


def accelerations(line: LumpedLine, r, v, fair_r, fair_v):
    """The moving nodes' accelerations (N - 1, 3) for positions r and velocities v, the fairlead at
    fair_r moving at fair_v."""
    return _rates(line, r, v, fair_r, fair_v)[0]


def fairlead_force(line: LumpedLine, r, v, fair_r, fair_v):
    """The line's force on the fairlead (3,), inertial: the last segment's tension along it plus the
    fairlead node's half segment of weight, drag and seabed contact (as MoorDyn hands a line end's
    loads to its connection; the half segment's inertia is left out)."""
    r_all = _nodes(line, r, fair_r)
    v_all = _nodes(line, v, fair_v).at[0].set(0.0)
    T, q = segment_tensions(line, r_all, v_all)
    loads, _, _ = _node_loads(line, r_all, v_all)
    return -T[-1] * q[-1] + loads[-1]


def anchor_force(line: LumpedLine, r, v, fair_r, fair_v):
    """The line's force on the anchor (3,): the first segment's tension plus the anchor node's half segment."""
    r_all = _nodes(line, r, fair_r)
    v_all = _nodes(line, v, fair_v).at[0].set(0.0)
    T, q = segment_tensions(line, r_all, v_all)
    loads, _, _ = _node_loads(line, r_all, v_all)
    return T[0] * q[0] + loads[0]


def hermite(p0, v0, p1, v1, h, tau):
    """Position and velocity at t_n + tau h of the cubic with positions and velocities p, v at both ends."""
    t2, t3 = tau * tau, tau * tau * tau
    pos = ((2 * t3 - 3 * t2 + 1) * p0 + (t3 - 2 * t2 + tau) * h * v0 + (-2 * t3 + 3 * t2) * p1
           + (t3 - t2) * h * v1)
    vel = ((6 * t2 - 6 * tau) * p0 / h + (3 * t2 - 4 * tau + 1) * v0 + (-6 * t2 + 6 * tau) * p1 / h
           + (3 * t2 - 2 * tau) * v1)
    return pos, vel


def advance(line: LumpedLine, s: LineState, fair0, fair_v0, fair1, fair_v1, h, substeps=None) -> LineState:
    """The moving nodes at t_n + h from those at t_n, the fairlead at (fair0, fair_v0) at t_n and
    (fair1, fair_v1) at t_n + h: `substeps` (static; default: from the stability limit) symplectic
    Euler sub-steps in a `lax.scan`. The dissipated work and the fairlead's work add each
    sub-step's power at its start (the point its acceleration is taken at): the line's energy
    balance (`energies`) then holds to the scheme's first order in the sub-step."""
    k = line.substeps(h) if substeps is None else int(substeps)
    dt = h / k

    def one(c, i):
        r, v, lost, work = c
        fr, fv = hermite(fair0, fair_v0, fair1, fair_v1, h, i / k)
        a, p_lost, p_fair = _rates(line, r, v, fr, fv)
        v = v + dt * a
        return (r + dt * v, v, lost + dt * p_lost, work + dt * p_fair), None

    zero = jnp.zeros((), s.r.dtype)
    (r, v, lost, work), _ = jax.lax.scan(one, (s.r, s.v, zero + s.dissipated, zero + s.work),
                                         jnp.arange(k, dtype=s.r.dtype))
    return LineState(r, v, lost, work)


def potential(line: LumpedLine, r, fair):
    """The line's potential energy (J): elastic, weight (w z) and the seabed's springs."""
    r_all = _nodes(line, r, fair)
    ln = _norm(r_all[1:] - r_all[:-1])
    e = ln / line.seg - 1.0
    elastic = line.ea * line.seg * jnp.sum(_ramp_int(e, STRAIN_BAND))
    share = jnp.full((line.segments + 1,), line.seg).at[0].set(0.5 * line.seg).at[-1].set(0.5 * line.seg)
    grav = line.weight * jnp.sum(share * r_all[:, 2])
    p = line.seabed_z - r_all[:, 2]
    bed = line.diameter * line.seabed_stiffness * jnp.sum(share * _ramp_int(p, SEABED_BAND))
    return elastic + grav + jnp.where(jnp.isfinite(line.seabed_z), bed, 0.0)


def kinetic(line: LumpedLine, r, v, fair):
    """The moving nodes' kinetic energy with their added mass (J)."""
    e = energies(line, r, v, fair)
    return e["kinetic"] + e["added_kinetic"]


def energies(line: LumpedLine, r, v, fair) -> dict:
    """The line's energies (J) for the moving nodes at r with velocities v, the fairlead at `fair`:
    `kinetic` (the nodes' own mass), `added_kinetic` (the water's, through the added mass),
    `elastic` (the segments' strain energy), `weight` (the moving nodes' submerged weight w l z, z
    in the line's frame) and `seabed` (its springs' energy). The end nodes' half segments are left
    out: their weight and contact load the anchor and the fairlead's body, not the line. With the
    fairlead held and no drag or damping their sum is constant; with them, it falls by the dissipated
    work and rises by the fairlead's (`LineState`), exactly where the added mass is isotropic (ca
    normal = tangential) or zero; otherwise the tangent's turning exchanges some energy with the
    water that no term holds (the node's added mass is taken along its current tangent, as MoorDyn)."""
    r_all = _nodes(line, r, fair)
    e = _norm(r_all[1:] - r_all[:-1]) / line.seg - 1.0
    d = r_all[1:] - r_all[:-1]
    qs = d / _norm(d)[:, None]
    t = qs[:-1] + qs[1:]
    t = t / _norm(t)[:, None]
    vol = jnp.pi * line.diameter ** 2 / 4.0 * line.seg
    vt, vv = jnp.sum(v * t, axis=-1), jnp.sum(v * v, axis=-1)
    bed = line.diameter * line.seabed_stiffness * line.seg * jnp.sum(_ramp_int(line.seabed_z - r[:, 2], SEABED_BAND))
    return {"kinetic": 0.5 * line.mass * line.seg * jnp.sum(vv),
            "added_kinetic": 0.5 * line.rho * vol * jnp.sum(line.ca[0] * vv + (line.ca[1] - line.ca[0]) * vt * vt),
            "elastic": line.ea * line.seg * jnp.sum(_ramp_int(e, STRAIN_BAND)),
            "weight": line.weight * line.seg * jnp.sum(r[:, 2]),
            "seabed": jnp.where(jnp.isfinite(line.seabed_z), bed, 0.0)}


def _start_shape(line: LumpedLine, fair):
    """A start near the static shape: the inextensible catenary with a seabed run (its horizontal
    tension by bisection on XF = L - L_s + a acosh(1 + ZF / a), a = H / w, L_s = sqrt(ZF^2 + 2 a ZF)
    the suspended length); where that has no seabed run (or the line is buoyant), an L shape: a
    seabed run and a straight rise whose lengths add up to the line's (straight from anchor to
    fairlead when that is longer than the line)."""
    a0 = line.anchor
    dx = fair[:2] - a0[:2]
    XF = jnp.sqrt(jnp.sum(dx * dx) + 1e-30)
    ZF = jnp.maximum(fair[2] - a0[2], 1e-9)
    L = line.length
    s = jnp.arange(1, line.segments) / line.segments * L

    def gap(a):
        Ls = jnp.sqrt(ZF * ZF + 2.0 * a * ZF)
        return L - Ls + a * jnp.arccosh(1.0 + ZF / a) - XF

    def bisect(_, lohi):
        lo, hi = lohi
        mid = jnp.sqrt(lo * hi)
        up = gap(mid) < 0.0        # gap grows with a: too little horizontal span, raise a
        return jnp.where(up, mid, lo), jnp.where(up, hi, mid)

    lo, hi = jax.lax.fori_loop(0, 200, bisect, (1e-6 * L, 1e6 * L))
    a = jnp.sqrt(lo * hi)
    Lb = L - jnp.sqrt(ZF * ZF + 2.0 * a * ZF)
    sig = jnp.maximum(s - Lb, 0.0)
    x_cat = jnp.where(s <= Lb, s, Lb + a * jnp.arcsinh(sig / a))
    z_cat = jnp.where(s <= Lb, 0.0, a * (jnp.sqrt(1.0 + (sig / a) ** 2) - 1.0))
    cat_ok = (line.weight > 0) & (Lb > 0) & (jnp.abs(gap(a)) < 1e-6 * L)
    D = jnp.sqrt(XF * XF + ZF * ZF)
    Lr = jnp.clip((L * L - D * D) / (2.0 * jnp.maximum(L - XF, 1e-9)), 0.0, XF)
    Lr = jnp.where(D >= L, 0.0, Lr)
    rise = jnp.sqrt((XF - Lr) ** 2 + ZF ** 2)
    sl = s / L * (Lr + rise)
    frac = jnp.clip((sl - Lr) / jnp.maximum(rise, 1e-9), 0.0, 1.0)
    x_l = jnp.where(sl <= Lr, sl, Lr + frac * (XF - Lr))
    z_l = jnp.where(sl <= Lr, 0.0, frac * ZF)
    x = jnp.where(cat_ok, x_cat, x_l)
    z = jnp.where(cat_ok, z_cat, z_l)
    e = dx / XF
    return jnp.stack([a0[0] + x * e[0], a0[1] + x * e[1], a0[2] + z], axis=-1)


def static_shape(line: LumpedLine, fair, tol=1e-8, max_iter=200):
    """The moving nodes (N - 1, 3) in static equilibrium with the fairlead at `fair`: the minimum
    of `potential`, by Levenberg-Marquardt steps on its exact Hessian (a trial that does not lower
    the energy is refused and the damping raised), until the largest out-of-balance force is below
    tol times the weight of a segment. Returns (nodes, converged)."""
    x0 = _start_shape(line, fair).reshape(-1)
    pot = lambda x: potential(line, x.reshape(-1, 3), fair)  # noqa: E731
    grad = jax.grad(pot)
    hess = jax.hessian(pot)
    fscale = jnp.abs(line.weight) * line.seg + 1e-12 * line.ea

    def cond(c):
        x, mu, it, gmax = c
        return (gmax > tol * fscale) & (it < max_iter)

    def body(c):
        x, mu, it, _ = c
        g = grad(x)
        H = hess(x)
        dH = jnp.abs(jnp.diag(H)) + 1e-12 * line.ea / line.seg
        dx = jnp.linalg.solve(H + mu * jnp.diag(dH), -g)
        p_old, p_new = pot(x), pot(x + dx)
        # near the minimum a step's energy change falls to the energy's round-off (a stiff chain: EA
        # 1e9 N, forces of mN against 1e9 J): a step that keeps the energy within that and lowers the
        # largest force is taken too, or the damping would only grow there
        flat = p_new <= p_old + 64 * jnp.finfo(p_old.dtype).eps * jnp.abs(p_old)
        better = (p_new < p_old) | (flat & (jnp.max(jnp.abs(grad(x + dx))) < jnp.max(jnp.abs(g))))
        x = jnp.where(better, x + dx, x)
        mu = jnp.where(better, mu * 0.3, mu * 4.0)
        return x, jnp.maximum(mu, 1e-12), it + 1, jnp.max(jnp.abs(grad(x)))

    x, mu, it, gmax = jax.lax.while_loop(cond, body, (x0, jnp.asarray(1.0), 0, jnp.asarray(jnp.inf)))
    return x.reshape(-1, 3), gmax <= tol * fscale


def static_shape_traced(line: LumpedLine, fair, tol=1e-8, max_iter=200):
    """`static_shape` for a line whose values (length, weight, EA) or fairlead are traced: the solve
    runs on their values with no derivative through its loop (reverse mode cannot pass a while
    loop), and the derivative comes from the equilibrium instead (implicit function theorem: grad
    V(x*, p) = 0 gives dx*/dp = -H^-1 d(grad V)/dp), added as a term whose value is zero so that the
    nodes are the solve's to the last bit. Returns (nodes, converged)."""
    held = jax.tree_util.tree_map(jax.lax.stop_gradient, (line, fair))
    x, ok = static_shape(*held, tol=tol, max_iter=max_iter)
    x = jax.lax.stop_gradient(x.reshape(-1))
    g = jax.grad(lambda y: potential(line, y.reshape(-1, 3), fair))(x)
    H = jax.hessian(lambda y: potential(held[0], y.reshape(-1, 3), held[1]))(x)
    dx = jnp.linalg.solve(H, g)
    return (x - (dx - jax.lax.stop_gradient(dx))).reshape(-1, 3), ok
