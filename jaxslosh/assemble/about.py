"""What assembly writes on the terms where their arrays alone cannot say it (physics/about.py): a
tank's name, shape, mesh and element; a structure's mesh and attachment; the sea's parameters and
the source of its forces; a hull's file; a record's columns. Each function gives the `About` of one
term that assemble/system.py (or a builder it calls) makes, and is called only where that term is
made: `jaxslosh check` lists the model's terms, never the scene's wishes (assemble/check.py)."""
from __future__ import annotations

import os

from ..hydro.source import excitation_source
from ..physics.about import About
from ..scene.types import Scene
from ..liquid.forms import tank_liquid
from .effects import interface_unknowns, structure_modes, structure_unknowns


def weight_about(scene: Scene, nonlinear: bool) -> About:
    """The Weight term's line: what holds the vessel up, if anything (a vessel with its linear
    hydrostatics table has no weight term: its weight is balanced, buoyancy switched on or off)."""
    if nonlinear:
        return About(("gravity", "the weight of the ship and its liquid, borne by the hull's pressure"))
    g = scene.environment.gravity
    if scene.vessel.forced is not None:    # its rows are the prescribed motion's (System.hold): nothing falls
        liquid = "; the liquid sloshes under gravity" if scene.tanks and g > 0 else ""
        return About(("gravity", ("the vessel's weight moves nothing: its motion is prescribed ([vessel.forced])" + liquid)
                                 if g > 0 else "environment.gravity = 0: no weight"))
    return About(("gravity", "no hydrostatics table: the vessel falls freely" if g > 0 else
                             "environment.gravity = 0: no weight"))


def hull_about(scene: Scene, waves: bool, hull=None) -> About:
    """HullPressure's lines: the nonlinear buoyancy on the hull's wetted surface (the vessel's, or
    `hull`, a body's), and the incident waves' pressure there where it has them."""
    hull = scene.vessel.hull if hull is None else hull
    what = hull.describe()
    lines = [("buoyancy", f"nonlinear: the still-water pressure on the instantaneous wetted surface of the {what}, "
                          "clipped exactly at the water")]
    if waves:
        lines.append(("waves", f"{sea_words(scene.waves)}; their Froude-Krylov pressure (Wheeler-stretched) on the "
                               "same wetted surface (nonlinear)"))
    return About(*lines)


def tank_line(t) -> tuple[str, str]:
    """One tank's liquid, as the liquid term holds it (the model's words: AbstractLiquid.describe_tank)."""
    return tank_liquid(t).describe_tank(t).line


def liquid_about(scene: Scene, include_liquid: bool) -> About:
    """The deformable block's lines: each tank's liquid and elastic walls, and the structures in the
    vessel's frame that share the block."""
    lines = []
    for t in scene.tanks if include_liquid else ():
        words = tank_liquid(t).describe_tank(t)
        lines += [words.line, *words.walls]
    for s in scene.structures:
        if s.frame == "vessel":
            nx, ny, nz = s.mesh
            lines.append((f"flexible structure {s.name!r}",
                          f"{nx}x{ny}x{nz} elastic hexahedra (incompatible modes) deforming in the vessel's frame, "
                          f"its {s.attach} face held on the vessel ({structure_unknowns(s)} unknowns)"))
    return About(*lines)


def stiffening_about(scene: Scene, frame: str) -> About:
    """The centrifugal stiffening of the structures in `frame` ("vessel": SpinStiffening; "own": Flex)."""
    return About(*((f"centrifugal stiffening of {s.name!r}", "geometric stiffness of the stress of its spin")
                   for s in scene.structures if s.frame == frame and s.stiffening == "centrifugal"))


def flex_about(scene: Scene) -> About:
    """The structures in their own floating frames (physics/structures.py Structures)."""
    lines = []
    for s in scene.structures:
        if s.frame != "own":
            continue
        nx, ny, nz = s.mesh
        to = f"structure {s.attach_to!r}" if s.attach_to else "the vessel"
        lines.append((f"flexible structure {s.name!r}",
                      f"{nx}x{ny}x{nz} elastic hexahedra (incompatible modes), its own floating frame (6 unknowns) "
                      f"and {structure_modes(s)} elastic modes; its {s.attach} face tied to {to} through an "
                      f"interface frame and localized multipliers ({interface_unknowns(s)} unknowns)"))
    return About(*lines) + stiffening_about(scene, "own")


def damping_about(scene: Scene) -> About:
    """ModalDamping's lines: each damped tank's ratio (and boundary layers)."""
    lines = []
    for t in scene.tanks:
        if t.damping is None:
            continue
        d = t.damping
        ratio = list(d.ratio) if isinstance(d.ratio, tuple) else d.ratio
        layers = f" plus laminar boundary layers (viscosity {d.viscosity:g} m^2/s)" if d.viscosity else ""
        lines.append((f"liquid damping in tank {t.name!r}",
                      f"modal damping of {tank_liquid(t).describe_tank(t).damped}, ratio {ratio}{layers}"))
    return About(*lines)


def record_about(f) -> About:
    """RecordedMotion's line: the record's columns and samples."""
    dofs = ", ".join(name for name, _ in f.columns)
    return About(("prescribed motion", f"{dofs} from {os.path.basename(f.file)} ({len(f.times)} samples, t = "
                                       f"{f.times[0]:g} to {f.times[-1]:g} s) by a natural cubic spline "
                                       f"(continuous acceleration), other rigid dofs held"))


def sea_words(w) -> str:
    """The sea of a `[waves]` table, in a few words."""
    return f"{w.describe()}, heading {w.heading:.4g} rad" + (f", faded in over {w.ramp:g} s" if w.ramp > 0 else "")


def waves_about(scene: Scene, nonlinear: bool) -> About:
    """WaveExcitation's line: the sea and where its forces come from. With the nonlinear hull the
    incident waves' Froude-Krylov pressure acts on the wetted hull (HullPressure says so, and the
    sea): this term holds only the diffraction, the tables less the hull's linear Froude-Krylov."""
    if nonlinear:
        return About(("wave diffraction", "the excitation tables less the hull's linear Froude-Krylov force, on the "
                                          "rigid rows"))
    src = excitation_source(scene)
    src = ("Froude-Krylov on the box hull" if src == "froude-krylov" else
           "Capytaine (Froude-Krylov + diffraction)" if scene.vessel.hydrodynamics.capytaine else "excitation tables")
    return About(("waves", f"{sea_words(scene.waves)}; forces from {src}"))


def _radiation_source(scene: Scene) -> str:
    hd = scene.vessel.hydrodynamics
    return "Capytaine" if hd.capytaine else f"tables at {len(hd.frequencies)} frequencies"


def added_mass_about(scene: Scene) -> About:
    return About(("radiation", f"added mass at infinite frequency, from {_radiation_source(scene)}"))


def memory_about(scene: Scene) -> About:
    return About(("radiation memory", "the memory of the Cummins equation (state-space fit of the radiation "
                                      f"damping), from {_radiation_source(scene)}"))


def viscous_about() -> About:
    return About(("viscous damping", "linear, [vessel.hydrodynamics] viscous_damping"))
