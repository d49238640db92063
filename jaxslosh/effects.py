"""Which physical effects a scene simulates: only those it calls for (the model is assembled from
the scene, so an effect the scene lacks is never traced)."""
from __future__ import annotations

from .scene_types import Scene


def scene_effects(scene: Scene) -> list[tuple[str, str]]:
    """(effect, why) for every effect the scene's model contains."""
    eff = [("rigid-body inertia", "vessel: 6 unknowns, rotations on the group (|q| = 1 exactly)")]
    if scene.vessel.hydrostatics is not None:
        eff.append(("buoyancy", "restoring force and moments of eqs. (33)-(36), "
                                f"moment form {scene.vessel.hydrostatics.moment!r}"))
    elif scene.environment.gravity > 0:
        eff.append(("gravity", "no hydrostatics table: the vessel falls freely"))
    for t in scene.tanks:
        eff.append((f"liquid in tank {t.name!r}", f"{t.mesh[0]}x{t.mesh[1]}x{t.mesh[2]} hexahedra, "
                    f"{t.liquid_mass:.6g} kg, element {t.fluid.element!r}, {t.walls} walls (slip)"))
    if scene.tanks:
        eff.append(("centrifugal and Coriolis terms", "liquid moving in the rotating vessel frame (eq. 19)"))
        if scene.environment.gravity > 0:
            eff.append(("gravity turning with the body", "load of eq. (32) on the liquid"))
    return eff


def count_unknowns(scene: Scene) -> int:
    n = 6
    for t in scene.tanks:
        nx, ny, nz = t.mesh
        nodes = (nx + 1) * (ny + 1) * (nz + 1)
        fixed = 2 * (ny + 1) * (nz + 1) + 2 * (nx + 1) * (nz + 1) + (nx + 1) * (ny + 1)
        n += 3 * nodes - fixed
    return n


def effects_summary(scene: Scene) -> str:
    lines = ["effects simulated:"]
    lines += [f"  - {name}: {why}" for name, why in scene_effects(scene)]
    lines.append(f"unknowns per step: {count_unknowns(scene)}")
    return "\n".join(lines)
