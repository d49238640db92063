"""The scene as `jaxslosh check` describes it (its title, vessel, tanks, structures, probes and
steps) and its unknowns, counted from the scene before anything is built (assemble/cost.py reads
them too). The effects `check` lists are the assembled model's own (assemble/check.py)."""
from __future__ import annotations


from ..liquid.forms import tank_liquid
from ..liquid.words import shape_words, wall_unknowns, walls_words
from ..scene.types import EFFECTS, Scene
from ..solve.schemes import SCHEMES


def describe(scene: Scene) -> str:
    """A few lines: title, vessel, tanks, structures, probes and steps (warnings are not included)."""
    ves, sim = scene.vessel, scene.simulation
    lines = [f"{scene.title or '(untitled)'}" + (f"  [{scene.path}]" if scene.path else "")]
    diag = ", ".join(f"{ves.inertia[i][i]:.4g}" for i in range(3))
    h = ves.hydrostatics
    hydro = (f"A_w {h.waterplane_area:g} m^2, V {h.displaced_volume:g} m^3, GM_T {h.gm_t:g} m, GM_L {h.gm_l:g} m"
             + (" (the hull's at rest; the restoring is nonlinear)" if h.nonlinear else "")
             if h is not None else "no hydrostatics (its motion prescribed by [vessel.forced])"
             if ves.forced is not None else "no hydrostatics (free body)")
    lines.append(f"vessel: mass {ves.mass:.4g} kg, inertia diagonal [{diag}] kg m^2; {hydro}")
    for t in scene.tanks:
        lines.append(f"tank {t.name!r}: {shape_words(t)}{t.size[0]:g} x {t.size[1]:g} x {t.size[2]:g} m filled to "
                     f"{t.fill_depth:g} m, liquid {t.liquid_mass:.4g} kg ({t.liquid_volume:.4g} m^3), "
                     f"{mesh_words(t)}, walls {walls_words(t)}")
        lines += tank_notes(t)
    for s in scene.structures:
        nx, ny, nz = s.mesh
        mass = s.material.density * s.size[0] * s.size[1] * s.size[2]
        lines.append(f"structure {s.name!r}: {s.size[0]:g} x {s.size[1]:g} x {s.size[2]:g} m, {mass:.4g} kg, "
                     f"mesh {nx} x {ny} x {nz}, attached at {s.attach}")
    if scene.probes:
        lines.append("probes: " + ", ".join(
            f"{p.name} ({'tank' if p.tank else 'structure'} {p.tank or p.structure!r} at "
            f"[{', '.join(f'{x:g}' for x in p.point)}])" for p in scene.probes))
    lines.append(f"simulation: {sim.n_steps} steps of {sim.dt:g} s to t = {sim.n_steps * sim.dt:g} s, "
                 f"scheme {sim.scheme}{SCHEMES[sim.scheme].settings_words(sim)}, saving every {sim.save_every} step(s)")
    return "\n".join(lines)



def structure_unknowns(s) -> int:
    """Unknowns a structure adds: in the vessel's frame, its nodes' dofs less the held face's; in its
    own frame, its frame, its modes and its interface's."""
    if s.frame == "vessel":
        nx, ny, nz = s.mesh
        return 3 * ((nx + 1) * (ny + 1) * (nz + 1) - face_nodes(s))
    return 6 + structure_modes(s) + interface_unknowns(s)


def face_nodes(s) -> int:
    """The nodes on a structure's attached face."""
    nx, ny, nz = s.mesh
    axis = "xyz".index(s.attach[0])
    return [(ny + 1) * (nz + 1), (nx + 1) * (nz + 1), (nx + 1) * (ny + 1)][axis]


def structure_modes(s) -> int:
    """The elastic modes a structure in its own frame keeps: all its nodes' dofs less the six rigid."""
    nx, ny, nz = s.mesh
    return 3 * (nx + 1) * (ny + 1) * (nz + 1) - 6


def interface_unknowns(s) -> int:
    """The interface frame's positions and the multipliers of its two sides."""
    return 9 * face_nodes(s)


def switched_off(scene: Scene) -> list[str]:
    return [k for k in EFFECTS if not getattr(scene.effects, k)]


def mesh_words(t) -> str:
    """What the tank's liquid is discretized into, as the model that runs its form says it
    (AbstractLiquid.describe_tank): "mesh 5 x 5 x 5 = 125 hexahedra", a mesh file's counts, or a
    multimodal tank's modes (it has no mesh)."""
    return tank_liquid(t).describe_tank(t).mesh


def tank_notes(t) -> list[str]:
    """Indented lines under a tank: each baffle as the model reads it (its plane, side and edge), a
    nearly full horizontal cylinder's unresolved free surface, and how many hexahedra of a mesh file
    were re-oriented (numbered left-handed in the file): the shape's notes (jaxslosh/geometry)."""
    return t.geometry.notes(t.fill_depth, tuple(t.mesh))


def free_liquid_dofs(tank) -> int:
    """A tank's free liquid unknowns at full order, as the model that runs its form counts them
    (liquid/base.py `AbstractLiquid.tank_unknowns`): the nodal elements' three dofs per node, less the
    wall-normal ones the slip walls hold; the face-normal element's free faces; a multimodal tank's
    modal coordinates."""
    return tank_liquid(tank).tank_unknowns(tank)


def liquid_unknowns(scene: Scene) -> int:
    """Unknowns of the full-order liquid block: every tank's free liquid dofs, and its elastic walls'."""
    n = 0
    for t in scene.tanks:
        n += free_liquid_dofs(t) + wall_unknowns(t)
    return n


def count_unknowns(scene: Scene) -> int:
    n = 6 + sum(structure_unknowns(s) for s in scene.structures) + 6 * len(scene.bodies)
    if not scene.effects.liquid:
        return n
    # the bodies' tanks counted as the vessel's are, their elastic walls' unknowns included
    return n + liquid_unknowns(scene) + sum(free_liquid_dofs(t) + wall_unknowns(t) for b in scene.bodies for t in b.tanks)
