"""Modal analysis of a tank's liquid with the vessel held fixed (`jaxslosh modes`)."""
from __future__ import annotations

from .scene_types import Scene


def sloshing_modes(scene: Scene, tank=None, n: int = 10):
    """The first n modes of a tank's liquid: `Modes(omega, kind, free_surface_share, shapes)`."""
    from .liquid import build_liquid
    from .modes import liquid_modes
    from .effects import free_liquid_dofs
    from .sparse import SPARSE_AUTO
    t = scene.tank(tank) if tank is not None else scene.tanks[0]
    # large meshes as the simulation takes them: sparse matrices and shift-invert Lanczos (a dense
    # generalized eigh of 20 x 20 x 12 needs 2 GB a matrix and crashed OpenBLAS)
    large = t.wall_spec is None and free_liquid_dofs(t) > SPARSE_AUTO
    model = build_liquid(t.size, t.fill_depth, t.mesh, t.fluid.density, t.fluid.sound_speed,
                         scene.environment.gravity, element=t.fluid.element, sparse=large)
    if t.wall_spec is not None:       # the liquid and its elastic walls together (kinds add "wall")
        from .tankwalls import build_tank_with_walls, tank_modes
        return tank_modes(build_tank_with_walls(t, model), n=n)
    return liquid_modes(model, n=n)


def structure_modes(scene: Scene, structure: str, n: int = 10):
    """The first n modes of a flexible structure held at its attachment face (the vessel, or the
    structure it is attached to, held fixed): `StructureModes(omega, kind, shares, shapes)`; each mode
    named by the pattern of its cross-sections that holds most of its kinetic energy (bending along
    an axis, torsion, axial, other)."""
    from .structure import build_structure, clamped_modes, face_nodes
    st = scene.structure(structure)
    m = build_structure(st.size, st.mesh, st.material.young, st.material.poisson, st.material.density)
    return clamped_modes(m, face_nodes(m.nodes, m.size, st.attach), n=n)


def effective_roll_inertia(size, mesh, element="stabilized", density=1000.0, sound_speed=1500.0, gravity=9.81,
                           absolute_rotation=True, omegas=(0.02, 0.04)):
    """Low-frequency effective roll inertia of the liquid in a full, closed tank (a lid on top).

    The tank rolls harmonically about the x axis through the liquid's centroid, theta(t) =
    theta0 exp(i W t), slowly (W well below every liquid mode); the liquid's relative motion is
    solved in the frequency domain, (K - W^2 M) d = W^2 M (e_x x r) theta0 - K_dt theta0, and the
    moment the tank must apply, -W^2 I_eff theta0 + (a stiffness), is fitted over two frequencies.
    Returns (I_eff, I_frozen_discrete, I_frozen_exact) in kg m^2. With `absolute_rotation=False`
    the rotation penalty acts on the relative rotation only (the liquid turns with the tank).
    An inviscid liquid does not spin up: Stokes-Joukowski gives 0.1565 I_frozen for a square
    section, 0.45 for a 2:1 one (PHYSICS.md item 5)."""
    import numpy as np

    from .liquid import build_liquid
    a, b, h = (float(s) for s in size)
    m = build_liquid((a, b, h), h, mesh, density, sound_speed, gravity, element=element)
    nodes = np.asarray(m.nodes)
    free = np.asarray(m.free).reshape(-1, 3).copy()
    free[np.abs(nodes[:, 2] - h) < 1e-9 * h, 2] = False                # the lid
    f = free.reshape(-1)
    M3 = np.kron(np.asarray(m.mass), np.eye(3))
    K = np.asarray(m.stiffness)
    r = nodes - np.array([a / 2, b / 2, h / 2])
    ex = np.array([1.0, 0.0, 0.0])
    u_rot = np.cross(ex, r).reshape(-1)                                 # rigid rotation field per unit theta
    C = np.asarray(m.rotation_coupling) if (absolute_rotation and m.rotation_coupling is not None) else None
    moments = []
    for W in omegas:
        rhs = W ** 2 * (M3 @ u_rot)
        if C is not None:
            rhs = rhs - C[:, 0]
        d = np.zeros(3 * len(nodes))
        d[f] = np.linalg.solve((K - W ** 2 * M3)[np.ix_(f, f)], rhs[f])
        # rate of the liquid's angular momentum about the centroid, per unit theta0
        Hdot = -W ** 2 * np.cross(r, (M3 @ (d + u_rot)).reshape(-1, 3)).sum(axis=0)[0]
        reaction = 0.0
        if C is not None:
            reaction = C[:, 0] @ d + np.asarray(m.rotation_stiffness)[0, 0]
        moments.append(Hdot + reaction)
    W2 = np.array(omegas) ** 2
    I_eff = -(moments[1] - moments[0]) / (W2[1] - W2[0])
    I_frozen_discrete = u_rot @ M3 @ u_rot
    I_frozen_exact = density * a * b * h * (b * b + h * h) / 12.0
    return float(I_eff), float(I_frozen_discrete), float(I_frozen_exact)
