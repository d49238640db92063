"""What `jaxslosh check` prints: a scene described, the effects its model simulates (only those it
calls for: the model is assembled from the scene, so an effect the scene lacks, or switches off in
`[effects]`, is never traced) and its unknowns."""
from __future__ import annotations

import os

from ..fem.walls import shell_mesh
from ..hydro.source import excitation_source
from ..scene.types import EFFECTS, Scene


def describe(scene: Scene) -> str:
    """A few lines: title, vessel, tanks, structures, probes and steps (warnings are not included)."""
    ves, sim = scene.vessel, scene.simulation
    lines = [f"{scene.title or '(untitled)'}" + (f"  [{scene.path}]" if scene.path else "")]
    diag = ", ".join(f"{ves.inertia[i][i]:.4g}" for i in range(3))
    h = ves.hydrostatics
    hydro = (f"A_w {h.waterplane_area:g} m^2, V {h.displaced_volume:g} m^3, GM_T {h.gm_t:g} m, GM_L {h.gm_l:g} m"
             + (" (the hull's at rest; the restoring is nonlinear)" if h.nonlinear else "")
             if h is not None else "no hydrostatics (free body)")
    lines.append(f"vessel: mass {ves.mass:.4g} kg, inertia diagonal [{diag}] kg m^2; {hydro}")
    for t in scene.tanks:
        walls = t.walls if t.wall_spec is None else f"elastic, {t.wall_spec.thickness:g} m thick"
        lines.append(f"tank {t.name!r}: {shape_words(t)}{t.size[0]:g} x {t.size[1]:g} x {t.size[2]:g} m filled to "
                     f"{t.fill_depth:g} m, liquid {t.liquid_mass:.4g} kg ({t.liquid_volume:.4g} m^3), "
                     f"{mesh_words(t)}, walls {walls}")
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
    damping = {"newmark": ", energy projection" if sim.energy_projection else "", "hht": f", alpha {sim.alpha:g}", "generalized-alpha": f", rho_inf {sim.rho_inf:g}"}
    lines.append(f"simulation: {sim.n_steps} steps of {sim.dt:g} s to t = {sim.n_steps * sim.dt:g} s, "
                 f"scheme {sim.scheme}{damping[sim.scheme]}, saving every {sim.save_every} step(s)")
    return "\n".join(lines)



def scene_effects(scene: Scene) -> list[tuple[str, str]]:
    """(effect, what it is) for every effect the scene's model contains."""
    e = scene.effects
    eff = [("rigid-body inertia", "vessel: 6 unknowns, rotations on the group (|q| = 1 exactly)")]
    if scene.vessel.forced is not None:
        f = scene.vessel.forced
        if f.profile == "spin-up":
            eff.append(("prescribed motion", f"{f.dof} rate spun up to {f.rate:g} rad/s over {f.duration:g} s, "
                                             "other rigid dofs held"))
        elif f.profile == "record":
            dofs = ", ".join(name for name, _ in f.columns)
            eff.append(("prescribed motion", f"{dofs} from {os.path.basename(f.file)} ({len(f.times)} samples, t = "
                                             f"{f.times[0]:g} to {f.times[-1]:g} s) by a natural cubic spline "
                                             f"(continuous acceleration), other rigid dofs held"))
        else:
            phase = f" + {f.phase:g}" if f.phase else ""
            ramp = f", faded in over {f.ramp:g} s" if f.ramp else ""
            eff.append(("prescribed motion", f"{f.dof} = {f.amplitude:g} sin({f.frequency:g} t{phase}){ramp}, "
                                             f"other rigid dofs held"))
    if scene.vessel.hydrostatics is not None and e.buoyancy and scene.vessel.hydrostatics.nonlinear:
        hull = scene.vessel.hull
        what = (f"box {hull.length:g} x {hull.beam:g} x {hull.depth:g} m (deck included)" if hull.type == "box"
                else f"mesh {hull.file}")
        waves = " and the incident waves' (Wheeler-stretched Froude-Krylov)" if scene.waves is not None and e.waves else ""
        eff.append(("buoyancy", f"nonlinear: the still-water pressure{waves} on the instantaneous wetted surface of "
                                f"the {what}, clipped exactly at the water; the weight of the ship and its liquid"))
    elif scene.vessel.hydrostatics is not None and e.buoyancy:
        eff.append(("buoyancy", "restoring force and moments of eqs. (33)-(36), "
                                f"moment form {scene.vessel.hydrostatics.moment!r}"))
    elif scene.vessel.hydrostatics is None and scene.environment.gravity > 0:
        eff.append(("gravity", "no hydrostatics table: the vessel falls freely"))
    liquid = bool(scene.tanks) and e.liquid
    if liquid:
        for t in scene.tanks:
            eff.append((f"liquid in tank {t.name!r}", f"{shape_words(t)}{mesh_words(t, short=True)}, "
                        f"{t.liquid_mass:.6g} kg, element {t.fluid.element!r}{element_why(t)}, {t.walls} walls (slip)"))
            if t.damping is not None:
                d = t.damping
                ratio = list(d.ratio) if isinstance(d.ratio, tuple) else d.ratio
                layers = f" plus laminar boundary layers (viscosity {d.viscosity:g} m^2/s)" if d.viscosity else ""
                eff.append((f"liquid damping in tank {t.name!r}",
                            f"modal damping of the sloshing modes, ratio {ratio}{layers}"))
            if t.wall_spec is not None:
                eff.append((f"elastic walls of tank {t.name!r}",
                            f"{t.wall_spec.thickness:g} m thick, {t.wall_mass:.6g} kg of elastic hexahedra built into "
                            "the hull (the vessel's frame), the liquid tied to them in the normal direction only"))
        if e.coriolis:
            eff.append(("Coriolis", "2 omega x d_dot on the liquid (eq. 19)"))
        if e.centrifugal:
            eff.append(("centrifugal", "omega x (omega x r) on the liquid (eq. 19)"))
        if scene.environment.gravity > 0 and e.gravity_turning:
            eff.append(("gravity turning with the body", "load of eq. (32) on the liquid"))
    for s in scene.structures:
        nx, ny, nz = s.mesh
        to = f"structure {s.attach_to!r}" if s.attach_to else "the vessel"
        if s.frame == "vessel":
            eff.append((f"flexible structure {s.name!r}",
                        f"{nx}x{ny}x{nz} elastic hexahedra (incompatible modes) deforming in the vessel's frame, its "
                        f"{s.attach} face held on the vessel ({_unknowns(s)} unknowns)"))
        else:
            eff.append((f"flexible structure {s.name!r}",
                        f"{nx}x{ny}x{nz} elastic hexahedra (incompatible modes), its own floating frame (6 unknowns) "
                        f"and {_structure_modes(s)} elastic modes; its {s.attach} face tied to {to} through an "
                        f"interface frame and localized multipliers ({_interface_unknowns(s)} unknowns)"))
        if s.stiffening == "centrifugal":
            eff.append((f"centrifugal stiffening of {s.name!r}", "geometric stiffness of the stress of its spin"))
    eff += _wave_effects(scene)
    return eff


def _unknowns(s) -> int:
    """Unknowns a structure adds (frame = "vessel": its nodes' dofs less the held face's)."""
    if s.frame == "vessel":
        nx, ny, nz = s.mesh
        return 3 * ((nx + 1) * (ny + 1) * (nz + 1) - _face_nodes(s))
    return 6 + _structure_modes(s) + _interface_unknowns(s)


def _face_nodes(s) -> int:
    nx, ny, nz = s.mesh
    axis = "xyz".index(s.attach[0])
    return [(ny + 1) * (nz + 1), (nx + 1) * (nz + 1), (nx + 1) * (ny + 1)][axis]


def _structure_modes(s) -> int:
    nx, ny, nz = s.mesh
    return 3 * (nx + 1) * (ny + 1) * (nz + 1) - 6


def _interface_unknowns(s) -> int:
    return 9 * _face_nodes(s)          # frame positions and the multipliers of its two sides


def _wave_effects(scene: Scene) -> list[tuple[str, str]]:
    """Waves and hull hydrodynamics (waves.py, hydrodynamics.py), as build.py assembles them."""
    e, w, ves = scene.effects, scene.waves, scene.vessel
    out = []
    if w is not None and e.waves:
        src = excitation_source(scene)
        nl = ves.hydrostatics is not None and ves.hydrostatics.nonlinear and e.buoyancy
        src = ("Froude-Krylov on the wetted hull (nonlinear)" if nl and src == "froude-krylov" else
               "the tables less the hull's linear Froude-Krylov (diffraction), and Froude-Krylov on the wetted hull "
               "(nonlinear)" if nl else
               "Froude-Krylov on the box hull" if src == "froude-krylov" else
               "Capytaine (Froude-Krylov + diffraction)" if ves.hydrodynamics.capytaine else "excitation tables")
        sea = (f"regular, amplitude {w.amplitude:g} m, {w.omega:.4g} rad/s" if w.type == "regular" else
               (f"JONSWAP Hs {w.hs:g} m, Tp {w.tp:g} s, gamma {w.gamma:g}" if w.type == "jonswap" else
                f"Pierson-Moskowitz Hs {w.hs:g} m, Tp {w.tp:g} s")
               + f", {w.components} components, seed {w.seed}"
               + (f", cos-2s spreading s = {w.spreading:g} over {w.directions} headings" if w.spreading > 0 else ""))
        out.append(("waves", f"{sea}, heading {w.heading:.4g} rad; forces from {src}"
                             + (f", faded in over {w.ramp:g} s" if w.ramp > 0 else "")))
    hd = ves.hydrodynamics
    if hd is not None and e.radiation:
        if hd.capytaine or hd.added_mass is not None:
            where = "Capytaine" if hd.capytaine else f"tables at {len(hd.frequencies)} frequencies"
            out.append(("radiation", f"added mass at infinite frequency and the memory of the Cummins equation "
                                     f"(state-space fit), from {where}"))
        if hd.viscous_damping is not None:
            out.append(("viscous damping", "linear, [vessel.hydrodynamics] viscous_damping"))
    return out


def switched_off(scene: Scene) -> list[str]:
    return [k for k in EFFECTS if not getattr(scene.effects, k)]


def mesh_words(t, short: bool = False) -> str:
    """"mesh 5 x 5 x 5 = 125 hexahedra" (a grid, of any shape, or a mesh file that is one), or
    "mesh file of 12 hexahedra on 30 nodes" (a mesh tank's file that is not a grid: its counts
    along x, y, z mean nothing)."""
    nx, ny, nz = t.mesh
    words = t.geometry.mesh_words()
    if words is not None:
        return words
    return f"{nx}x{ny}x{nz} hexahedra" if short else f"mesh {nx} x {ny} x {nz} = {nx * ny * nz} hexahedra"


def shape_words(t) -> str:
    """"prismatic (chamfers ...) " and the like for a tank that is not a plain box, else ""."""
    if t.geometry.plain_box:
        return ""
    return t.geometry.describe() + ", "


def tank_notes(t) -> list[str]:
    """Indented lines under a tank: each baffle as the model reads it (its plane, side and edge), a
    nearly full horizontal cylinder's unresolved free surface, and how many hexahedra of a mesh file
    were re-oriented (numbered left-handed in the file): the shape's notes (jaxslosh/geometry)."""
    return t.geometry.notes(t.fill_depth, tuple(t.mesh))


def free_liquid_dofs(tank) -> int:
    """A tank's free liquid dofs: three per node, less the wall-normal ones the slip walls hold."""
    if not tank.geometry.plain_box:
        return tank.geometry.free_count(tank.fill_depth, tuple(tank.mesh))
    nx, ny, nz = tank.mesh
    nodes = (nx + 1) * (ny + 1) * (nz + 1)
    return 3 * nodes - (2 * (ny + 1) * (nz + 1) + 2 * (nx + 1) * (nz + 1) + (nx + 1) * (ny + 1))


def liquid_unknowns(scene: Scene) -> int:
    """Unknowns of the full-order liquid block: every tank's free liquid dofs, and its elastic walls'."""
    n = 0
    for t in scene.tanks:
        n += free_liquid_dofs(t)
        if t.wall_spec is not None:       # the walls' free nodes (the liquid's normal dofs share theirs)
            _, _, _, held = shell_mesh(t.size, t.fill_depth, t.mesh, t.wall_spec.thickness, t.wall_spec.mesh)
            n += 3 * int((~held).sum())
    return n


def count_unknowns(scene: Scene) -> int:
    n = 6 + sum(_unknowns(s) for s in scene.structures)
    if not scene.effects.liquid:
        return n
    return n + liquid_unknowns(scene)


def effects_summary(scene: Scene) -> str:
    lines = ["effects simulated:"]
    lines += [f"  - {name}: {why}" for name, why in scene_effects(scene)]
    off = switched_off(scene)
    if off:
        lines.append("switched off in [effects]: " + ", ".join(off))
    lines.append(f"unknowns per step: {count_unknowns(scene)}")
    return "\n".join(lines)


def element_why(t) -> str:
    """`check`'s note on a liquid element the scene left out: which one the loader chose, and why
    (scene/shape.py default_element); a given element needs none. Face-normal tanks say how they run."""
    runs = ""
    if t.fluid.element == "rt":
        runs = f" on {t.reduction.modes} modes" if t.reduction is not None else " at full order"
    if not t.fluid.element_default or t.model != "fem":
        return runs
    return f"{runs} (by default: {t.fluid.element_default})"
