"""The angles of vanishing stability a run's capsize check holds its roll and pitch against
(validity.py), for a vessel with the nonlinear hydrostatics: the righting lever GZ of its hull at
fixed heels from 0 to 180 degrees, free to sink to the ship's displacement (tank liquid frozen at
rest, its weight in the centre of gravity), the trim held (hull/hydrostatics.gz_curve), and the
first heel where GZ turns from righting to capsizing. `js.stability` (analysis/stability.py) draws
the full curve with the trim free and the liquids level; this is the quick bound a run needs, for
any closed hull it has."""
from __future__ import annotations

from typing import Optional

import jax.numpy as jnp
import numpy as np

from ..hull.hydrostatics import first_vanishing, gz_curve
from ..physics.bodies import bodies_term
from ..physics.hull import HullPressure
from ..physics.vessel import Weight

#: heels at which GZ is evaluated before the crossing is interpolated, 0 to 180 degrees by 2
HEELS = 91


def vanishing_angles(system) -> Optional[tuple]:
    """(roll, pitch) angles of vanishing stability (rad; None where GZ stays positive) of a built
    System with the nonlinear hydrostatics; None for other systems."""
    return _angles(system.terms)


def body_vanishing_angles(system) -> dict:
    """{name: (roll, pitch) angles of vanishing stability} of the [[bodies]] of a built System that
    float on their own hull with the nonlinear hydrostatics (the same hull and weight terms as the
    vessel's, its tanks' liquid in its weight); the other bodies are left out."""
    term = bodies_term(system)
    if term is None:
        return {}
    angles = {name: _angles(f.terms) for name, f in zip(term.names, term.bodies)}
    return {name: a for name, a in angles.items() if a is not None}


def _angles(terms) -> Optional[tuple]:
    hull = [t for t in terms if isinstance(t, HullPressure)]
    weight = [t for t in terms if isinstance(t, Weight)]
    if not hull or not weight:
        return None
    h, w = hull[0], weight[0]
    angles = np.linspace(0.0, np.pi, HEELS)
    return tuple(first_vanishing(angles, gz_curve(h.surface(), h.z_water, w.mass / h.rho_w, w.S / w.mass,
                                                  jnp.asarray(angles), axis)) for axis in (0, 1))


def capsize_reason(roll, pitch, angles, body: Optional[str] = None) -> Optional[str]:
    """Why a run's record (roll and pitch series, rad) counts as capsized against its angles of
    vanishing stability (vanishing_angles), or None: the first axis whose largest |angle| passes
    its angle. A campaign gives this as the case's status, so the case counts as not operable and
    as exceeding every limit. `body`: the record is that [[bodies]] body's (body_vanishing_angles),
    named in the reason as the run's capsize watch names it."""
    if angles is None:
        return None
    for name, x, limit in (("roll", roll, angles[0]), ("pitch", pitch, angles[1])):
        peak = float(np.max(np.abs(np.asarray(x)))) if np.size(x) else 0.0
        if limit is not None and peak > limit:
            what = f"the {name}" if body is None else f"the body {body!r}'s {name}"
            return (f"capsized: {what} reached {np.degrees(peak):.1f} deg, past {'the' if body is None else 'its'} "
                    f"hull's angle of vanishing stability {np.degrees(limit):.1f} deg")
    return None


def case_capsize(roll_pitch_yaw, angles, bodies: dict) -> Optional[str]:
    """Why a campaign case capsized, or None: the vessel's record (roll_pitch_yaw (n, 3)) against its
    `angles`, then each body's, `bodies` = {name: (its roll_pitch_yaw (n, 3), its angles)} in the
    bodies' order (capsize_reason): the first that passed its angle."""
    rpy = np.asarray(roll_pitch_yaw)
    why = capsize_reason(rpy[:, 0], rpy[:, 1], angles)
    for name, (r, a) in bodies.items():
        if why is not None:
            break
        r = np.asarray(r)
        why = capsize_reason(r[:, 0], r[:, 1], a, name)
    return why
