"""From a validated scene to the static model: `System`, probes and the initial state.

Only what the scene has is built (STYLE.md: Python branches on static model data): a vessel
without tanks has no liquid block, a scene without `[vessel.hydrostatics]` no buoyancy.
Numbers named in `params` (dotted TOML paths) replace the scene's values and may be JAX tracers,
which is what makes `jax.grad` through `simulate(scene, params=...)` work.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import jax.numpy as jnp
import numpy as np

from .kinematics import quat_from_rpy
from .model import Config, Forced, Hydro, Liquid, System
from .scene_types import Scene, SceneError

class _Keys(tuple):
    """The traceable keys; `<name>` in an entry stands for the name of any tank of the scene
    (`tanks.<name>.fill_depth` holds `tanks.tank.fill_depth`)."""

    def __contains__(self, key) -> bool:
        if not isinstance(key, str):
            return False
        for pattern in self:
            if "<name>" not in pattern:
                if key == pattern:
                    return True
                continue
            head, tail = pattern.split("<name>")
            if key.startswith(head) and key.endswith(tail) and len(key) > len(head) + len(tail):
                if not any(ch in key[len(head):len(key) - len(tail)] for ch in ".[]/"):
                    return True
        return False


# Scene values that simulate(params=...) may replace by traced values (the vessel is rebuilt per
# call; the liquid matrices are assembled from traced fill depth, density, sound speed and gravity).
TANK_TRACEABLE = ("fill_depth", "fluid.density", "fluid.sound_speed")
TRACEABLE = _Keys((
    "environment.gravity", "environment.water_density", "vessel.mass", "vessel.inertia",
    "vessel.hydrostatics.waterplane_area", "vessel.hydrostatics.displaced_volume",
    "vessel.hydrostatics.gm_t", "vessel.hydrostatics.gm_l",
    "vessel.initial.position", "vessel.initial.velocity", "vessel.initial.angular_velocity",
    "vessel.initial.roll_pitch_yaw",
) + tuple(f"tanks.<name>.{k}" for k in TANK_TRACEABLE) + ("waves.amplitude", "waves.hs"))


class TankBlock(NamedTuple):
    """Where one tank's liquid sits in the stacked liquid block, for probes and result fields."""
    name: str
    node_offset: int
    nodes: np.ndarray      # (N_t, 3) tank-local
    elements: np.ndarray   # (E_t, 8) tank-local node indices
    model: object          # liquid.LiquidModel


class Probes(NamedTuple):
    names: tuple
    points: jnp.ndarray    # (P, 3) undeformed positions in the vessel frame
    weights: jnp.ndarray   # (P, N) interpolation of the liquid displacement (zero rows: the probe follows the tank)


class Built(NamedTuple):
    system: System
    c0: Config
    v0: jnp.ndarray
    probes: Probes
    tanks: tuple


def _inertia(value):
    a = jnp.asarray(value, dtype=float)
    return jnp.diag(a) if a.ndim == 1 else a


def _params_get(params, key, default):
    return params[key] if key in params else default


def check_params(params) -> None:
    for k in params:
        if k not in TRACEABLE:
            raise SceneError(k, "cannot be overridden in simulate(params=...) (traceable: " + ", ".join(TRACEABLE) + ")")


def build(scene: Scene, params: Optional[dict] = None) -> Built:
    params = _canonical_params(scene, dict(params or {}))
    check_params(params)
    P = lambda k, d: _params_get(params, k, d)  # noqa: E731
    env, ves = scene.environment, scene.vessel
    g = jnp.asarray(P("environment.gravity", env.gravity), dtype=float)
    eff = scene.effects
    hydro = None
    if ves.hydrostatics is not None and eff.buoyancy:
        h = ves.hydrostatics
        hydro = Hydro(
            rho_w=jnp.asarray(P("environment.water_density", env.water_density), dtype=float), gravity=g,
            waterplane_area=jnp.asarray(P("vessel.hydrostatics.waterplane_area", h.waterplane_area), dtype=float),
            displaced_volume=jnp.asarray(P("vessel.hydrostatics.displaced_volume", h.displaced_volume), dtype=float),
            gm_t=jnp.asarray(P("vessel.hydrostatics.gm_t", h.gm_t), dtype=float),
            gm_l=jnp.asarray(P("vessel.hydrostatics.gm_l", h.gm_l), dtype=float),
            moment_form=h.moment)
    liquid, tanks, d0 = _build_liquid(scene, params, g) if eff.liquid else (None, (), None)
    forced = None
    if ves.forced is not None:
        f = ves.forced
        dofs = ("surge", "sway", "heave", "roll", "pitch", "yaw")
        forced = Forced(dof=dofs.index(f.dof), amplitude=jnp.asarray(f.amplitude, dtype=float),
                        frequency=jnp.asarray(f.frequency, dtype=float), ramp=float(f.ramp))
    ini = ves.initial
    q0 = quat_from_rpy(jnp.asarray(P("vessel.initial.roll_pitch_yaw", ini.roll_pitch_yaw), dtype=float))
    if forced is not None:
        q0 = jnp.array([1.0, 0.0, 0.0, 0.0])
    g_fixed = None
    if liquid is not None and not eff.gravity_turning:
        from .kinematics import rotation_matrix
        g_fixed = rotation_matrix(q0).T @ jnp.array([0.0, 0.0, -g])
    sea = None
    if scene.waves is not None or ves.hydrodynamics is not None:   # waves and hull hydrodynamics
        from .hydrodynamics import build_seakeeping
        sea = build_seakeeping(scene, params)
    system = System(mass=jnp.asarray(P("vessel.mass", ves.mass), dtype=float),
                    inertia=_inertia(P("vessel.inertia", ves.inertia)), gravity=g, hydro=hydro, liquid=liquid,
                    forced=forced, g_fixed=g_fixed, q_ref=q0, balanced=ves.hydrostatics is not None,
                    coriolis=eff.coriolis, centrifugal=eff.centrifugal, sea=sea)
    nf = system.nf
    d_init = jnp.zeros(nf)
    if liquid is not None:
        d_init = _hydrostatic_start(system, q0)
    c0 = Config(jnp.asarray(P("vessel.initial.position", ini.position), dtype=float), q0, d_init)
    v0 = jnp.concatenate([jnp.asarray(P("vessel.initial.velocity", ini.velocity), dtype=float),
                          jnp.asarray(P("vessel.initial.angular_velocity", ini.angular_velocity), dtype=float),
                          jnp.zeros(nf)])
    if forced is not None:   # the prescribed motion sets the rigid state at t = 0
        c0 = Config(jnp.zeros(3), q0, c0.d)
        v0 = v0.at[:6].set(forced.rates(jnp.zeros(())))
    probes = _build_probes(scene, tanks, liquid)
    return Built(system, c0, v0, probes, tanks)


def _build_liquid(scene: Scene, params: Optional[dict] = None, gravity=None):
    """The stacked liquid block of all tanks. `params` (canonical keys) may replace each tank's
    fill depth, density and sound speed, and `gravity` the scene's, by traced values: then the
    matrices are JAX values (the integer mesh, the free dofs and the probes' host-side geometry
    stay NumPy).

    The host-side tank blocks (`TankBlock.nodes`, used for the probes' interpolation weights and the
    result's undeformed mesh) are the mesh at the scene's fill depth, whatever the params say: a
    probe keeps its place relative to the mesh (one at the scene's fill depth stays on the free
    surface), so its weights do not depend on a traced fill depth."""
    rigid = [t for t in scene.tanks]
    if not rigid:
        return None, (), None
    for i, t in enumerate(rigid):
        if t.walls != "rigid":
            raise SceneError(f"tanks[{i}].walls", "elastic tank walls are not supported yet (use \"rigid\")")
    from .liquid import build_liquid  # the liquid module is only imported by scenes that have liquid

    params = params or {}
    g = scene.environment.gravity if gravity is None else gravity
    models = []
    for t in rigid:
        P = lambda k, d: params.get(f"tanks.{t.name}.{k}", d)  # noqa: E731
        models.append(build_liquid(t.size, P("fill_depth", t.fill_depth), t.mesh, P("fluid.density", t.fluid.density),
                                   P("fluid.sound_speed", t.fluid.sound_speed), g, element=t.fluid.element))
    traced = any(m.traced for m in models)
    xp = jnp if traced else np

    blocks, rs, Ms_list, K_list, free_list, Kdt_list, Ktt = [], [], [], [], [], [], xp.zeros((3, 3))
    coupled = False
    offset = 0
    for t, m in zip(rigid, models):
        N = m.nodes.shape[0]
        host_nodes = np.asarray(m.nodes) if not m.traced and m.depth == t.fill_depth else None
        if host_nodes is None:      # the mesh at the scene's fill depth (see above)
            nx, ny, nz = m.mesh
            X, Y, Z = np.meshgrid(np.linspace(0, t.size[0], nx + 1), np.linspace(0, t.size[1], ny + 1),
                                  np.linspace(0, t.fill_depth, nz + 1), indexing="ij")
            host_nodes = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
        blocks.append(TankBlock(t.name, offset, host_nodes, np.asarray(m.elements), m))
        rs.append(xp.asarray(m.nodes) + xp.asarray(t.origin)[None, :])
        Ms_list.append(xp.asarray(m.mass))
        free = np.flatnonzero(np.asarray(m.free))
        K_list.append(xp.asarray(m.stiffness)[np.ix_(free, free)])
        if getattr(m, "rotation_coupling", None) is not None:
            coupled = True
            Kdt_list.append(xp.asarray(m.rotation_coupling)[free])
            Ktt = Ktt + xp.asarray(m.rotation_stiffness)
        else:
            Kdt_list.append(xp.zeros((free.size, 3)))
        free_list.append(free + 3 * offset)
        offset += N
    if traced:
        from jax.scipy.linalg import block_diag
    else:
        from scipy.linalg import block_diag
    liquid = Liquid(r=jnp.asarray(xp.concatenate(rs)), Ms=jnp.asarray(block_diag(*Ms_list)),
                    K=jnp.asarray(block_diag(*K_list)), free=jnp.asarray(np.concatenate(free_list)),
                    n_nodes=offset, Kdt=jnp.asarray(xp.concatenate(Kdt_list)) if coupled else None,
                    Ktt=jnp.asarray(Ktt) if coupled else None)
    return liquid, tuple(blocks), None


def _canonical_params(scene: Scene, params) -> dict:
    """Keys in their name form (`tanks[0].fill_depth` -> `tanks.tank.fill_depth`); a value given
    under both spellings is an error, and a tank key must name a tank of the scene."""
    from .scene import canonical_key
    out, given = {}, {}
    for k, v in params.items():
        c = canonical_key(scene, k) if isinstance(k, str) else k
        if c in out:
            raise SceneError(k, f"names the same value as {given[c]}; give it once")
        out[c], given[c] = v, k
        if isinstance(c, str) and c.startswith("tanks.") and c in TRACEABLE:
            if not any(c.startswith(f"tanks.{t.name}.") for t in scene.tanks):
                raise SceneError(k, "names no tank of this scene (tanks: "
                                    + (", ".join(t.name for t in scene.tanks) or "none") + ")")
    return out


def _hydrostatic_start(system: System, q0):
    """Discrete hydrostatic equilibrium K d0 = F_g under the initial gravity direction (PHYSICS.md
    item 6), so that the stiff acoustic modes are not excited by the start."""
    from .kinematics import rotation_matrix
    L = system.liquid
    g_b = rotation_matrix(q0).T @ jnp.array([0.0, 0.0, -system.gravity])
    F = L.free_part(L.m_nodes[:, None] * g_b[None, :])
    return jnp.linalg.solve(L.K, F)


def _build_probes(scene: Scene, tanks, liquid) -> Probes:
    names, pts, W = [], [], []
    N = 0 if liquid is None else liquid.n_nodes
    by_name = {b.name: b for b in tanks}
    for i, p in enumerate(scene.probes):
        w = np.zeros(N)
        if p.tank is not None:
            t = scene.tank(p.tank)
            pts.append(np.asarray(t.origin) + np.asarray(p.point))
            b = by_name.get(t.name)
            if b is not None:
                local = probe_weights(np.asarray(p.point), t.size, t.fill_depth, b.nodes, b.elements)
                w[b.node_offset:b.node_offset + b.nodes.shape[0]] = local
        else:
            raise SceneError(f"probes[{i}].structure", "probes on structures need flexible structures, not supported yet")
        names.append(p.name)
        W.append(w)
    return Probes(tuple(names), jnp.asarray(np.array(pts).reshape(-1, 3)), jnp.asarray(np.array(W, dtype=float).reshape(len(W), N)))


def probe_weights(point, size, depth, nodes, elements, eps=1e-9):
    """SPEC section 1: a probe at the fill depth follows the free surface (even at a wall), a probe
    inside the liquid follows the liquid particle, a probe on the bottom or on a wall below the
    surface (or in the air above the liquid) follows the tank. Between nodes, the hexahedron's
    trilinear shape functions interpolate."""
    x, y, z = point
    a, b = size[0], size[1]
    scale = max(a, b, depth)
    tol = eps * scale + 1e-12
    w = np.zeros(nodes.shape[0])
    at_surface = abs(z - depth) <= 1e-6 * scale
    if z > depth and not at_surface:
        return w
    on_wall = min(x, a - x, y, b - y, z) <= tol
    if on_wall and not at_surface:
        return w
    for el in elements:
        X = nodes[el]
        lo, hi = X.min(axis=0), X.max(axis=0)
        p = np.array([x, y, min(z, depth)])
        if np.all(p >= lo - tol) and np.all(p <= hi + tol):
            xi = np.clip((p - lo) / (hi - lo), 0.0, 1.0)
            for k, node in enumerate(el):
                corner = (X[k] - lo) / (hi - lo)     # 0 or 1 per axis
                w[node] = np.prod(np.where(corner > 0.5, xi, 1.0 - xi))
            return w
    return w
