"""From a validated scene to the static model: `System`, probes and the initial state.

Only what the scene has is built (STYLE.md: Python branches on static model data): a vessel
without tanks has no liquid block, a scene without `[vessel.hydrostatics]` no buoyancy.
Numbers named in `params` (dotted TOML paths) replace the scene's values and may be JAX tracers,
which is what makes `jax.grad` through `simulate(scene, params=...)` work.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp

from .kinematics import quat_from_rpy
from .model import Config, Forced, Hydro, Liquid, System
from .reduction import is_reduced
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
    on_structures: tuple = ()   # StructureProbes per structure that has probes
    modal: Optional[jnp.ndarray] = None   # (P, m, 3) weights @ basis, with a reduced liquid: probes from eta


class StructureProbes(NamedTuple):
    """Probes on structure `index`: rows `rows` of the probe table, points `r` in its frame (from its
    COG) and trilinear weights `W` (k, N_s) over its nodes."""
    index: int
    rows: np.ndarray
    r: jnp.ndarray
    W: jnp.ndarray


class Built(NamedTuple):
    system: System
    c0: Config
    v0: jnp.ndarray
    probes: Probes
    tanks: tuple
    alg0: Optional[jnp.ndarray] = None    # interface frame positions (and zero multipliers) at t = 0
    structures: tuple = ()               # host-side StructureBlock per structure (result fields)


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
    liquid, tanks, extra = _build_liquid(scene, params, g, include_liquid=eff.liquid)
    vstructs, carried = extra if extra else ((), [])
    forced = None
    if ves.forced is not None:
        f = ves.forced
        dofs = ("surge", "sway", "heave", "roll", "pitch", "yaw")
        forced = Forced(dof=dofs.index(f.dof), amplitude=jnp.asarray(f.amplitude, dtype=float),
                        frequency=jnp.asarray(f.frequency, dtype=float), ramp=float(f.ramp), profile=f.profile,
                        rate=float(f.rate), duration=float(f.duration) if f.duration else 1.0)
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
    own = [s for s in scene.structures if s.frame == "own"]
    flex, blocks = _build_flex(scene) if own else (None, ())
    mass, inertia = jnp.asarray(P("vessel.mass", ves.mass), dtype=float), _inertia(P("vessel.inertia", ves.inertia))
    hull_S = None
    carried = carried + [_rigid_part(b.model.mass, b.model.nodes + np.asarray(scene.structure(b.name).origin))
                         for b in blocks]
    if carried:       # the ship's mass and inertia include these parts: the hull is the rest (SPEC)
        mass, inertia, hull_S = _hull(mass, inertia, carried)
    system = System(mass=mass, inertia=inertia, gravity=g, hydro=hydro, liquid=liquid, hull_S=hull_S,
                    forced=forced, g_fixed=g_fixed, q_ref=q0, balanced=ves.hydrostatics is not None,
                    coriolis=eff.coriolis, centrifugal=eff.centrifugal, flex=flex, sea=sea)
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
    alg0 = None
    if flex is not None:
        c0, v0, alg0 = _flex_start(system, c0, v0)
    probes = _build_probes(scene, tanks, liquid, blocks, vstructs or ())
    if is_reduced(liquid):     # the frames keep eta; probes through the basis (run._frame)
        probes = probes._replace(modal=jnp.einsum("pn,knc->pkc", probes.weights, liquid.U))
    return Built(system, c0, v0, probes, tanks, alg0, blocks)


def _build_liquid(scene: Scene, params: Optional[dict] = None, gravity=None, include_liquid=True):
    """The stacked liquid block of all tanks. `params` (canonical keys) may replace each tank's
    fill depth, density and sound speed, and `gravity` the scene's, by traced values: then the
    matrices are JAX values (the integer mesh, the free dofs and the probes' host-side geometry
    stay NumPy).

    The host-side tank blocks (`TankBlock.nodes`, used for the probes' interpolation weights and the
    result's undeformed mesh) are the mesh at the scene's fill depth, whatever the params say: a
    probe keeps its place relative to the mesh (one at the scene's fill depth stays on the free
    surface), so its weights do not depend on a traced fill depth."""
    rigid = [t for t in scene.tanks] if include_liquid else []
    in_vessel_frame = [s for s in scene.structures if s.frame == "vessel"]
    if not rigid and not in_vessel_frame:
        return None, (), None
    from .liquid import build_liquid  # the liquid module is only imported by scenes that have liquid

    params = params or {}
    g = scene.environment.gravity if gravity is None else gravity
    from .sparse import wants_sparse
    sparse = wants_sparse(scene)
    models = []
    for i, t in enumerate(rigid):
        P = lambda k, d: params.get(f"tanks.{t.name}.{k}", d)  # noqa: E731
        models.append(build_liquid(t.size, P("fill_depth", t.fill_depth), t.mesh, P("fluid.density", t.fluid.density),
                                   P("fluid.sound_speed", t.fluid.sound_speed), g, element=t.fluid.element,
                                   sparse=sparse))
        if sparse and models[-1].traced:
            raise SceneError(f"tanks[{i}]", "a traced tank value (fill depth, density, sound speed or gravity in "
                                            "params or a sweep) needs the dense liquid matrices; this mesh uses the "
                                            "sparse solver: set simulation.linear_solver = \"dense\" if they fit")
    traced = any(m.traced for m in models)
    xp = jnp if traced else np
    reduced = [t.reduction is not None for t in rigid]
    elastic = [t.wall_spec is not None for t in rigid]
    if any(elastic) or in_vessel_frame:
        for i, t in enumerate(rigid):
            if reduced[i] or sparse or models[i].traced:
                raise SceneError(f"tanks[{i}].walls" if elastic[i] else f"tanks[{i}]",
                                 "elastic walls, and structures in the vessel's frame, need the full-order dense "
                                 "liquid with the scene's own values (no [tanks.reduction], no sparse solver, no "
                                 "traced tank values)")
        return _liquid_with_walls(rigid, models, in_vessel_frame)
    if any(reduced):
        return _reduced_liquid(scene, rigid, models, reduced, g)

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
        free = np.flatnonzero(np.asarray(m.free))
        if sparse:
            Ms_list.append(m.mass)
            K_list.append(m.stiffness.tocsr()[free][:, free])
        else:
            Ms_list.append(xp.asarray(m.mass))
            K_list.append(xp.asarray(m.stiffness)[np.ix_(free, free)])
        if getattr(m, "rotation_coupling", None) is not None:
            coupled = True
            Kdt_list.append(xp.asarray(m.rotation_coupling)[free])
            Ktt = Ktt + xp.asarray(m.rotation_stiffness)
        else:
            Kdt_list.append(xp.zeros((free.size, 3)))
        free_list.append(free + 3 * offset)
        offset += N
    if sparse:
        from .liquid import surface_bending_scale
        from .sparse import host_sparse
        Kdt = jnp.asarray(np.concatenate(Kdt_list)) if coupled else None
        meshes = [tuple(m.mesh) for m in models]
        nodes_of = [np.arange(m.nodes.shape[0]) for m in models]
        free_of = [np.flatnonzero(np.asarray(m.free)) for m in models]
        layers = tuple(m.layers for m in models)
        liquid = Liquid(r=jnp.asarray(np.concatenate(rs)),
                        Ms=host_sparse(sp.block_diag(Ms_list), tuple(zip(meshes, [1] * len(models), nodes_of)), layers),
                        K=host_sparse(sp.block_diag(K_list), tuple(zip(meshes, [3] * len(models), free_of)), layers),
                        free=jnp.asarray(np.concatenate(free_list)),
                        n_nodes=offset, Kdt=Kdt, Ktt=jnp.asarray(Ktt) if coupled else None,
                        grids=tuple(m.mesh + (surface_bending_scale(m), m.element) for m in models))
        return liquid, tuple(blocks), None
    if traced:
        from jax.scipy.linalg import block_diag
    else:
        from scipy.linalg import block_diag
    liquid = Liquid(r=jnp.asarray(xp.concatenate(rs)), Ms=jnp.asarray(block_diag(*Ms_list)),
                    K=jnp.asarray(block_diag(*K_list)), free=jnp.asarray(np.concatenate(free_list)),
                    n_nodes=offset, Kdt=jnp.asarray(xp.concatenate(Kdt_list)) if coupled else None,
                    Ktt=jnp.asarray(Ktt) if coupled else None)
    return liquid, tuple(blocks), None


def _liquid_with_walls(tanks, models, structures=()):
    """The stacked deformable block of the vessel's frame when some tank has elastic walls
    (tankwalls.py) or some structure has frame = "vessel": every tank's nodes (liquid, then its
    walls'), then those structures' nodes; the map from nodal dofs to unknowns (held ones map to the
    zero slot); the matrices on the unknowns; and the structures' centrifugal stiffness."""
    from scipy.linalg import block_diag

    from .structure import assemble, box_element, box_mesh, centrifugal_stiffness, face_nodes
    from .tankwalls import build_tank_with_walls
    blocks, rs, Ms_list, K_list, maps, reps, Kdt_list, Kg_parts = [], [], [], [], [], [], [], []
    carried_idx = []      # (block index, first carried node): elastic walls and vessel-frame structures
    coupled = False
    Ktt = np.zeros((3, 3))
    node_off, free_off = 0, 0
    for t, m in zip(tanks, models):
        blocks.append(TankBlock(t.name, node_off, np.asarray(m.nodes), np.asarray(m.elements), m))
        if t.wall_spec is not None:
            tw = build_tank_with_walls(t, m)
            nodes, Ms, K, dmap, rep, C = tw.nodes, tw.mass, tw.stiffness, tw.dof_map, tw.rep, tw.rotation_coupling
            carried_idx.append((len(rs), m.n_nodes))
        else:
            free = np.asarray(m.free).reshape(-1)
            dmap = np.where(free, np.cumsum(free) - 1, -1)
            rep = np.flatnonzero(free)
            nodes, Ms = np.asarray(m.nodes), np.asarray(m.mass)
            K = np.asarray(m.stiffness)[np.ix_(rep, rep)]
            C = None if m.rotation_coupling is None else np.asarray(m.rotation_coupling)[rep]
        rs.append(nodes + np.asarray(t.origin)[None, :])
        Ms_list.append(Ms)
        K_list.append(K)
        maps.append(np.where(dmap >= 0, dmap + free_off, -1))
        reps.append(rep + 3 * node_off)
        if C is not None:
            coupled = True
            Kdt_list.append(C)
            Ktt = Ktt + np.asarray(m.rotation_stiffness)
        else:
            Kdt_list.append(np.zeros((rep.size, 3)))
        node_off += nodes.shape[0]
        free_off += rep.size
    vstructs = []
    for st in structures:
        mat = st.material
        nodes, elements = box_mesh(st.size, st.mesh)
        hs = tuple(a / n for a, n in zip(st.size, st.mesh))
        Ke, Mse = box_element(*hs, mat.young, mat.poisson, mat.density)
        Kfull, Ms = assemble(nodes, elements, Ke, Mse)
        held = np.zeros(nodes.shape[0], dtype=bool)
        held[face_nodes(nodes, st.size, st.attach)] = True
        fr = ~np.repeat(held, 3)
        dmap = np.where(fr, np.cumsum(fr) - 1, -1)
        rep = np.flatnonzero(fr)
        if st.stiffening == "centrifugal":     # spin about axes through the vessel's COG
            sizes = np.tile(np.asarray(hs), (elements.shape[0], 1))
            Kg = centrifugal_stiffness(nodes, elements, sizes, Kfull, Ms, held, mat.young, mat.poisson,
                                       axis_point=-np.asarray(st.origin, dtype=float))
            Kg_parts.append((free_off, [k[np.ix_(rep, rep)] for k in Kg]))
        vstructs.append(VesselFrameStructure(st.name, node_off, nodes, elements))
        carried_idx.append((len(rs), 0))
        rs.append(nodes + np.asarray(st.origin)[None, :])
        Ms_list.append(Ms)
        K_list.append(Kfull[np.ix_(rep, rep)])
        maps.append(np.where(dmap >= 0, dmap + free_off, -1))
        reps.append(rep + 3 * node_off)
        Kdt_list.append(np.zeros((rep.size, 3)))
        node_off += nodes.shape[0]
        free_off += rep.size
    dof_map = np.concatenate(maps)
    dof_map = np.where(dof_map >= 0, dof_map, free_off)          # the zero slot after the unknowns
    Kg = None
    if Kg_parts:
        Kg = np.zeros((6, free_off, free_off))
        for off, parts in Kg_parts:
            n = parts[0].shape[0]
            for k in range(6):
                Kg[k, off:off + n, off:off + n] = parts[k]
    liquid = Liquid(r=jnp.asarray(np.concatenate(rs)), Ms=jnp.asarray(block_diag(*Ms_list)),
                    K=jnp.asarray(block_diag(*K_list)), free=jnp.asarray(np.concatenate(reps)), n_nodes=node_off,
                    Kdt=jnp.asarray(np.concatenate(Kdt_list)) if coupled else None,
                    Ktt=jnp.asarray(Ktt) if coupled else None, dof_map=jnp.asarray(dof_map),
                    Kg=None if Kg is None else jnp.asarray(Kg))
    carried = [_rigid_part(Ms_list[k], rs[k][n0:], n0) for k, n0 in carried_idx]
    return liquid, tuple(blocks), (tuple(vstructs), carried)


def _hull(mass, inertia, parts):
    """The hull's own mass, inertia about the origin and first moment: the ship's (mass, inertia
    about its COG at the origin) less the parts that carry their own (structures, elastic walls)."""
    m = sum(p[0] for p in parts)
    S = sum(p[1] for p in parts)
    I = sum(p[2] for p in parts)
    if not isinstance(mass, jax.core.Tracer):
        if float(mass) <= m:
            raise SceneError("vessel.mass", f"{float(mass):.6g} kg is the whole ship without its liquid, structures "
                                            f"and elastic walls included, but those alone weigh {m:.6g} kg")
        if np.min(np.linalg.eigvalsh(np.asarray(inertia) - I)) <= 0:
            raise SceneError("vessel.inertia", "is the whole ship's about its COG, structures and elastic walls "
                                               "included, but it is smaller than theirs alone (the hull's would not "
                                               f"be positive definite; theirs: {np.round(np.diag(I), 1).tolist()} kg m^2)")
    return mass - m, inertia - jnp.asarray(I), -jnp.asarray(S)


def _rigid_part(Ms, r, n0=0):
    """(mass, first moment, inertia about the origin) of the nodes n0... of a block with scalar mass Ms
    (consistent: the inertia a rigid motion of the nodes has in the dynamics)."""
    Ms = np.asarray(Ms)[n0:, n0:]
    r = np.asarray(r)
    mn = Ms.sum(axis=1)
    G = r.T @ Ms @ r                                                 # sum_ij Ms_ij r_i r_j^T
    return float(mn.sum()), mn @ r, np.trace(G) * np.eye(3) - G


class VesselFrameStructure(NamedTuple):
    """A structure with frame = "vessel" inside the vessel-frame block: its nodes (block-local from
    its min corner) start at `node_offset`."""
    name: str
    node_offset: int
    nodes: np.ndarray
    elements: np.ndarray


class StructureBlock(NamedTuple):
    """Host-side data of one structure: its model (structure.StructureModel) and where its modal
    coordinates sit in the stacked eta."""
    name: str
    index: int
    eta_offset: int
    model: object


def _build_flex(scene: Scene):
    """Each structure in its own floating frame (origin at its COG), tied at its `attach` face to an
    interface frame that the vessel is tied to as well (localized multipliers on both sides)."""
    from .multibody import Body, Flex, Interface, Side
    from .structure import build_structure, face_nodes
    bodies, interfaces, blocks, models = [], [], [], {}
    offset = 0
    own = [st for st in scene.structures if st.frame == "own"]
    for i, st in enumerate(own):
        mat = st.material
        m = build_structure(st.size, st.mesh, mat.young, mat.poisson, mat.density)
        models[st.name] = (i, m, np.asarray(st.origin, dtype=float))
        Kg = None
        if st.stiffening == "centrifugal":   # spin about axes through the vessel's COG, modal form
            from .structure import centrifugal_stiffness
            held = np.zeros(m.n_nodes, dtype=bool)
            held[face_nodes(m.nodes, m.size, st.attach)] = True
            sizes = np.tile(np.asarray([a / n for a, n in zip(m.size, m.mesh)]), (m.elements.shape[0], 1))
            Kg = jnp.asarray(np.stack([m.Phi.T @ k @ m.Phi for k in centrifugal_stiffness(
                m.nodes, m.elements, sizes, m.stiffness, m.mass, held, mat.young, mat.poisson,
                axis_point=-np.asarray(st.origin, dtype=float))]))
        bodies.append(Body(r=jnp.asarray(m.r), Ms=jnp.asarray(m.mass), Phi=jnp.asarray(m.Phi),
                           omega2=jnp.asarray(m.omega ** 2), mass=jnp.asarray(m.total_mass),
                           c0=jnp.asarray(models[st.name][2] + m.cog), Kg=Kg))
        blocks.append(StructureBlock(st.name, i, offset, m))
        offset += m.Phi.shape[1]
    for i, st in enumerate(own):
        _, m, origin = models[st.name]
        nodes = face_nodes(m.nodes, m.size, st.attach)
        points = origin[None, :] + m.nodes[nodes]           # vessel frame, from the vessel's COG
        if st.attach_to is None:                             # tied to the vessel
            other = Side(-1, jnp.asarray(nodes), jnp.asarray(points))
            m_ref = m.total_mass
        else:                                                # tied to another structure's coincident nodes
            j, mo, oo = models[st.attach_to]
            theirs = oo[None, :] + mo.nodes
            match = np.argmin(np.linalg.norm(points[:, None, :] - theirs[None, :, :], axis=2), axis=1)
            other = Side(j, jnp.asarray(match), jnp.asarray(points))
            m_ref = min(m.total_mass, mo.total_mass)
        L_ref = float(max(max(st.size), np.abs(points).max()))
        interfaces.append(Interface(sides=(other, Side(i, jnp.asarray(nodes), jnp.asarray(points))),
                                    m_ref=jnp.asarray(m_ref), L_ref=L_ref))
    return Flex(bodies=tuple(bodies), interfaces=tuple(interfaces)), tuple(blocks)


def _flex_start(system: System, c0: Config, v0):
    """Structures at rest relative to the vessel, undeformed: frames aligned with the vessel's, at
    their centres of gravity, moving with it; interface frames on the vessel's attachment points."""
    from .kinematics import rotation_matrix
    from .multibody import layout
    flex = system.flex
    L = layout(system)
    A = rotation_matrix(c0.q)
    V, om = v0[:3], v0[3:6]
    Xs = jnp.stack([c0.X0 + A @ b.c0 for b in flex.bodies])
    qs = jnp.tile(c0.q, (L.S, 1))
    c = c0._replace(Xs=Xs, qs=qs, eta=jnp.zeros(L.m))
    rig = jnp.concatenate([jnp.concatenate([V + A @ jnp.cross(om, b.c0), om]) for b in flex.bodies])
    v = jnp.concatenate([v0[:6], rig, v0[6:], jnp.zeros(L.m)])
    alg = []
    for itf in flex.interfaces:
        alg += [(c0.X0[None, :] + itf.sides[0].points @ A.T).reshape(-1), jnp.zeros(3 * itf.n * len(itf.sides))]
    return c, v, jnp.concatenate(alg)


def _host_block(t, m, offset) -> TankBlock:
    """The tank's block for probes and result fields, with the mesh at the scene's fill depth."""
    nx, ny, nz = m.mesh
    X, Y, Z = np.meshgrid(np.linspace(0, t.size[0], nx + 1), np.linspace(0, t.size[1], ny + 1),
                          np.linspace(0, t.fill_depth, nz + 1), indexing="ij")
    return TankBlock(t.name, offset, np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1), np.asarray(m.elements), m)


def _reduced_liquid(scene: Scene, tanks, models, reduced, g):
    """Every tank's liquid on its modal basis (reduction.py); the bases come from the scene's values."""
    from .liquid import build_liquid
    from .reduction import reduce_liquid
    for i, (t, r) in enumerate(zip(tanks, reduced)):
        if not r:
            raise SceneError(f"tanks[{i}].reduction", "reduce every tank or none: another tank has a "
                                                       "[tanks.reduction] table and this one has not")
    concrete = []
    for t, m in zip(tanks, models):
        if m.traced or _is_traced(g):
            m = build_liquid(t.size, t.fill_depth, t.mesh, t.fluid.density, t.fluid.sound_speed,
                             scene.environment.gravity, element=t.fluid.element)
        concrete.append(m)
    offsets, blocks, offset = [], [], 0
    for t, m in zip(tanks, models):
        offsets.append(offset)
        blocks.append(_host_block(t, m, offset))
        offset += m.n_nodes
    liquid = reduce_liquid(models, concrete, [t.origin for t in tanks], offsets,
                           [(t.reduction.modes, t.reduction.static_correction) for t in tanks])
    return liquid, tuple(blocks), None


def _is_traced(x) -> bool:
    import jax
    return isinstance(x, jax.core.Tracer)


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
    from .reduction import is_reduced
    L = system.liquid
    g_b = rotation_matrix(q0).T @ jnp.array([0.0, 0.0, -system.gravity])
    if is_reduced(L):
        return L.static_start(g_b)
    from .sparse import hydrostatic_start, is_sparse
    if is_sparse(L):
        return hydrostatic_start(L, g_b)
    F = L.free_part(L.m_nodes[:, None] * g_b[None, :])
    return jnp.linalg.solve(L.K, F)


def _build_probes(scene: Scene, tanks, liquid, structures=(), vstructs=()) -> Probes:
    names, pts, W = [], [], []
    N = 0 if liquid is None else liquid.n_nodes
    by_name = {b.name: b for b in tanks}
    on_struct = {}
    for i, p in enumerate(scene.probes):
        w = np.zeros(N)
        if p.tank is not None:
            t = scene.tank(p.tank)
            pts.append(np.asarray(t.origin) + np.asarray(p.point))
            b = by_name.get(t.name)
            if b is not None:
                local = probe_weights(np.asarray(p.point), t.size, t.fill_depth, b.nodes, b.elements)
                w[b.node_offset:b.node_offset + b.nodes.shape[0]] = local
        elif scene.structure(p.structure).frame == "vessel":     # in the vessel-frame block, like a liquid point
            st = scene.structure(p.structure)
            pts.append(np.asarray(st.origin) + np.asarray(p.point))
            vb = next(b for b in vstructs if b.name == st.name)
            w[vb.node_offset:vb.node_offset + vb.nodes.shape[0]] = block_weights(np.asarray(p.point), vb.nodes,
                                                                                 vb.elements)
        else:
            st = scene.structure(p.structure)
            pts.append(np.asarray(st.origin) + np.asarray(p.point))
            blk = next(b for b in structures if b.name == st.name)
            on_struct.setdefault(blk.index, []).append((i, np.asarray(p.point) - blk.model.cog,
                                                        block_weights(np.asarray(p.point), blk.model.nodes,
                                                                      blk.model.elements)))
        names.append(p.name)
        W.append(w)
    sp = tuple(StructureProbes(k, np.array([e[0] for e in v]), jnp.asarray(np.array([e[1] for e in v])),
                               jnp.asarray(np.array([e[2] for e in v]))) for k, v in sorted(on_struct.items()))
    return Probes(tuple(names), jnp.asarray(np.array(pts).reshape(-1, 3)),
                  jnp.asarray(np.array(W, dtype=float).reshape(len(W), N)), sp)


def block_weights(point, nodes, elements, tol=1e-9):
    """Trilinear weights (N,) of a point of a meshed block (any point inside or on it)."""
    scale = np.ptp(nodes, axis=0).max()
    w = np.zeros(nodes.shape[0])
    for el in elements:
        X = nodes[el]
        lo, hi = X.min(axis=0), X.max(axis=0)
        if np.all(point >= lo - tol * scale) and np.all(point <= hi + tol * scale):
            xi = np.clip((point - lo) / (hi - lo), 0.0, 1.0)
            for k, node in enumerate(el):
                corner = (X[k] - lo) / (hi - lo)
                w[node] = np.prod(np.where(corner > 0.5, xi, 1.0 - xi))
            return w
    return w


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
