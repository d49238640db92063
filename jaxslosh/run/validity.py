"""Whether a run stayed where its model holds: the linear liquid's free surface inside its tank, the
Newton residual at what its iterations can reach; and whether the vessel capsized (heeled past its
angle of vanishing stability, with the nonlinear hydrostatics: run/capsize.py). What is found goes
into the summary and the result file's `warnings` attribute (the run itself is not stopped: its
numbers may still be what the user wants to see).

The residual is judged against the level the Newton iterations themselves aim at, max(tolerance,
round-off floor), not the tolerance alone: the floor (solve/linear.Solver.noise times the largest
liquid unknown) is eps |K| |d|, which the liquid's stiff acoustic rows lift above a 1e-10 tolerance
at centimetres of sloshing (the shipped anti-roll tank: 2.8e-8 at 0.4 degrees of roll, within 3.5
times its floor). A residual at the floor is round-off, not a fault; one well above it is a step
whose iterations stalled. Displacements beyond the model's range are said by the free-surface check."""
from __future__ import annotations

import dataclasses

import jax
import numpy as np

from ..liquid.forms import tank_liquid
from ..physics.bodies import bodies_term
from ..physics.kinematics import rpy_from_quat
from ..liquid.multimodal.steep import DEFINITE_ON, DEFINITE_SOFT, STEEP_FULL, STEEP_ON
from ..scene.types import Scene

#: a frame residual this many times its level, max(tolerance, round-off floor), is reported (the
#: iterations accept a stall up to 100 times that level; at the floor, residuals come within a few
#: times of it, as round-off does)
RESIDUAL_FACTOR = 10.0
#: the free-surface slope past which a multimodal tank's waves are taken as breaking: tan 30 deg, the
#: limiting crest of Stokes's wave (120 degrees), where a modal surface z = zeta(x) stops holding
STEEP_SLOPE = float(np.tan(np.radians(30.0)))


def _surface_tables(scene: Scene):
    """Per tank with a modal free surface (a multimodal one), (offset of its modal amplitudes, the
    slope's rows (P, modes) or its x and y rows for a three-dimensional tank, the elevation's rows at
    the liquid's quadrature points (Q, modes), their weights (Q,), k_N, omega_N^2): what the slope,
    the crest index and the round-off floor (liquid/multimodal/steep.py) are read from, as the model
    that runs the tank's form gives them (AbstractLiquid.surface_table); none where a tank has none.
    And {offset: (modes, k, omega^2)} of the tanks whose rows keep fewer modes past their range (the
    table's steepness cut: their round-off floor is then that mode's)."""
    g = scene.environment.gravity
    tables = [tank_liquid(t).surface_table(t, g) for t in scene.tanks]
    if any(s is None for s in tables):
        return [], {}
    out, cuts, off = [], {}, 0
    for s in tables:
        out.append((off, s.slope, s.Z, s.w, s.kN, s.omega2))
        if s.cut is not None:
            cuts[off] = s.cut
        off += s.Z.shape[1]
    return out, cuts


def _crest_index(Z, w, kN, d):
    """(k,): ln(mean exp(k_N zeta)) of each frame's amplitudes d (k, modes), as the liquid forms it."""
    e = kN * (d @ Z.T)
    m = e.max(axis=1, keepdims=True)
    return m[:, 0] + np.log(np.exp(e - m) @ (w / w.sum()))


def _tank_label(i, t) -> str:
    return f"tanks[{i}] ({t.name!r})"


def _passed(q, angles, time, heel, t_heel, capsized) -> None:
    """Mark in place (heel, t_heel, capsized: per axis) the first frame whose |roll| or |pitch| of the
    attitudes q (k, 4) passes its angle of vanishing stability (None: never)."""
    rp = np.abs(np.asarray(rpy_from_quat(np.asarray(q)))[:, :2])
    for axis, limit in enumerate(angles):
        j = int(np.argmax(rp[:, axis]))
        if limit is not None and rp[j, axis] > limit and not capsized[axis]:
            capsized[axis] = True
            heel[axis], t_heel[axis] = rp[j, axis], time[j]


class Watch:
    """Extremes seen over the frames of a run, chunk by chunk. The tanks of [[bodies]] are watched
    by a Watch of their own per body (`watch_bodies`), fed from the frames' bodies' liquid unknowns."""

    def __init__(self, scene: Scene, noise: float = 0.0, label=_tank_label):
        self.scene = scene
        self.label = label                # (index among scene.tanks, tank) -> how the warnings name it
        self.on_bodies = []               # (Watch, liquid, its unknowns' slice, top rows per tank) per body
        self.noise = float(noise)       # the solver's round-off floor per unit of the liquid's unknowns
        n = len(scene.tanks) if scene.effects.liquid else 0
        self.low = np.full(n, np.inf)
        self.high = np.full(n, -np.inf)
        self.t_low = np.zeros(n)
        self.t_high = np.zeros(n)
        self.residual, self.t_residual, self.level = 0.0, 0.0, self.scene.simulation.tolerance
        self.vanishing = None                    # (roll, pitch) angles of vanishing stability, rad (or None)
        self.heel = np.zeros(2)                  # largest |roll|, |pitch| seen past them, and when
        self.t_heel = np.zeros(2)
        self.capsized = [False, False]
        # [[bodies]] on their own hulls: {name: [index among the bodies, angles, heel (2,), t_heel (2,), capsized (2,)]}
        self.body_capsize = {}
        # a two-dimensional tank on more modes than its rows keep past its range: (modes, k, omega^2) of
        # its highest kept mode, whose floor its rows have past STEEP_FULL, by offset (the liquid's answer)
        self.tables, self.cut = _surface_tables(scene) if n else ([], {})
        self.slope = np.zeros(len(self.tables))     # steepest free surface of each multimodal tank, and when
        self.t_slope = np.zeros(len(self.tables))
        self.crest = np.zeros(len(self.tables))     # largest crest index of each, and when it first passed STEEP_ON
        self.t_crest = np.full(len(self.tables), np.nan)
        self.third = {}          # by tank: the third-order system's modal mass polynomial (`watch_liquid`)
        self.margin = np.ones(len(self.tables))        # its smallest margin, and when it first fell below DEFINITE_ON
        self.t_margin = np.full(len(self.tables), np.nan)

    def watch_liquid(self, liquid) -> None:
        """Read the margin of positive definiteness of the liquid's third-order tanks (their modal mass
        polynomial scaled by the modal masses, liquid/multimodal/steep.definiteness) from the frames."""
        for i, t in enumerate(getattr(liquid, "tanks", ())[:len(self.tables)]):
            if hasattr(t, "exact"):
                d = 1.0 / np.sqrt(np.asarray(t.modal_mass()))
                D2 = np.outer(d, d)
                self.third[i] = (np.asarray(t.M0)[6:, 6:] * D2, np.asarray(t.M1)[6:, 6:] * D2[..., None],
                                 np.asarray(t.M2)[6:, 6:] * D2[..., None, None])

    def watch_bodies(self, built) -> None:
        """Watch the tanks each body carries (built: the run's assemble.system.Built) as the vessel's
        are: their free surface against roof and floor, a multimodal tank's slope and crests."""
        term = bodies_term(built.system)
        for bt in getattr(built, "body_tanks", ()):
            floating, body = term.bodies[bt.body], self.scene.bodies[bt.body]
            own = dataclasses.replace(self.scene, tanks=body.tanks)
            tops = bt.block.surfaces()        # the rows its liquid's surface_heave reads, as the vessel's
            sub = Watch(own, label=lambda i, t, b=body.name: f"tank {t.name!r} on the body {b!r}")
            sub.watch_liquid(floating.tank)
            self.on_bodies.append((sub, floating.tank, slice(bt.offset, bt.offset + floating.nf), tops))

    def watch_capsize(self, angles, bodies=None, names=()) -> None:
        """Check the frames' roll and pitch against these angles of vanishing stability (rad; None
        where the hull has none); `bodies` {name: angles} the same for [[bodies]] on their own hulls
        (capsize.body_vanishing_angles), `names` all the bodies' names in their order (the frames')."""
        self.vanishing = angles
        self.body_capsize = {n: [list(names).index(n), a, np.zeros(2), np.zeros(2), [False, False]]
                             for n, a in (bodies or {}).items()}

    def update(self, time, surface, residual, field=None, q=None, body_d=None, bodies=None):
        """time (k,), surface (k, tanks, 2), residual (k,) of the frames just computed; `field`
        (k, ...): their liquid unknowns (Frame.D), whose size sets each frame's round-off floor;
        `q` (k, 4): their attitudes; `body_d` (k, m): the bodies' tanks' liquid unknowns (Frame.body_d);
        `bodies` (k, S, 10): the bodies' poses (Frame.bodies, their quaternions at 3:7)."""
        time = np.asarray(time)
        if time.size == 0:
            return
        if bodies is not None:
            for i, angles, heel, t_heel, capsized in self.body_capsize.values():
                _passed(np.asarray(bodies)[:, i, 3:7], angles, time, heel, t_heel, capsized)
        for sub, liquid, sl, tops in self.on_bodies if body_d is not None else ():
            d = np.asarray(body_d, float).reshape(time.size, -1)[:, sl]
            heave = [np.asarray(jax.vmap(lambda x, i=i: liquid.surface_heave(x, i))(d)) for i in tops]
            sub.update(time, np.stack([np.stack([h.min(axis=1), h.max(axis=1)], -1) for h in heave], 1),
                       np.zeros(time.size), d)
        if self.vanishing is not None and q is not None:
            _passed(q, self.vanishing, time, self.heel, self.t_heel, self.capsized)
        surface = np.asarray(surface).reshape(time.size, -1, 2)
        for i in range(self.low.size):
            j, k = int(np.argmin(surface[:, i, 0])), int(np.argmax(surface[:, i, 1]))
            if surface[j, i, 0] < self.low[i]:
                self.low[i], self.t_low[i] = surface[j, i, 0], time[j]
            if surface[k, i, 1] > self.high[i]:
                self.high[i], self.t_high[i] = surface[k, i, 1], time[k]
        if field is not None and self.tables:
            d = np.asarray(field, float).reshape(time.size, -1)
            for i, (off, rows, Z, w, kN, _) in enumerate(self.tables):
                di = d[:, off:off + Z.shape[1]]
                s = np.sqrt(sum((di @ r.T) ** 2 for r in rows)).max(axis=1)
                j = int(np.argmax(s))
                if s[j] > self.slope[i]:
                    self.slope[i], self.t_slope[i] = s[j], time[j]
                a = _crest_index(Z, w, kN, di)
                self.crest[i] = max(self.crest[i], float(a.max()))
                if np.isnan(self.t_crest[i]) and (a > STEEP_ON).any():
                    self.t_crest[i] = time[int(np.argmax(a > STEEP_ON))]
                if i in self.third:
                    M0, M1, M2 = self.third[i]
                    lam = np.linalg.eigvalsh(M0 + np.einsum("abj,kj->kab", M1, di)
                                             + np.einsum("abjl,kj,kl->kab", M2, di, di))
                    mu = lam[:, 0] - DEFINITE_SOFT * np.log(np.exp(-(lam - lam[:, :1]) / DEFINITE_SOFT).sum(axis=1))
                    self.margin[i] = min(self.margin[i], float(mu.min()))
                    if np.isnan(self.t_margin[i]) and (mu < DEFINITE_ON).any():
                        self.t_margin[i] = time[int(np.argmax(mu < DEFINITE_ON))]
        residual = np.asarray(residual, float)
        level = np.full(time.size, self.scene.simulation.tolerance)
        if field is not None and self.noise > 0:
            d = np.abs(np.asarray(field, float).reshape(time.size, -1))
            if d.shape[1]:
                level = np.maximum(level, self.noise * d.max(axis=1))
        if field is not None:
            # a multimodal tank's own floor under high crests, as its Newton iterations take it
            # (liquid/multimodal/steep.roundoff_floor)
            raw = np.asarray(field, float).reshape(time.size, -1)
            for off, _, Z, w, kN, om2 in self.tables:
                b = raw[:, off:off + Z.shape[1]]
                k, o2 = np.full(time.size, kN), np.full(time.size, om2)
                cut = self.cut.get(off)
                if cut is not None:      # past STEEP_FULL its rows are its first modes' (the cut's)
                    past = _crest_index(Z, w, kN, b) >= STEEP_FULL
                    k, o2 = np.where(past, cut[1], k), np.where(past, cut[2], o2)
                level = np.maximum(level, np.finfo(float).eps * o2 * np.abs(b).max(axis=1)
                                   * np.exp(2.0 * k * (b @ Z.T).max(axis=1)))
        r = int(np.argmax(residual / level))
        if residual[r] / level[r] > self.residual / self.level:
            self.residual, self.t_residual, self.level = float(residual[r]), float(time[r]), float(level[r])

    def warnings(self) -> list[str]:
        out = []
        for axis, name in enumerate(("roll", "pitch")):
            if self.capsized[axis]:
                out.append(f"capsized: the {name} reached {np.degrees(self.heel[axis]):.1f} deg at t = "
                           f"{self.t_heel[axis]:.4g} s, past the hull's angle of vanishing stability "
                           f"{np.degrees(self.vanishing[axis]):.1f} deg (its GZ at the ship's displacement, free to "
                           f"sink, tank liquid frozen): the vessel capsized")
        for name, (_, angles, heel, t_heel, capsized) in self.body_capsize.items():
            for axis, what in enumerate(("roll", "pitch")):
                if capsized[axis]:
                    out.append(f"capsized: the body {name!r}'s {what} reached {np.degrees(heel[axis]):.1f} deg at "
                               f"t = {t_heel[axis]:.4g} s, past its hull's angle of vanishing stability "
                               f"{np.degrees(angles[axis]):.1f} deg (its GZ at its displacement, free to sink, tank "
                               f"liquid frozen): the body capsized")
        for i, t in enumerate(self.scene.tanks[:self.low.size]):
            if not np.isfinite(self.low[i]):
                continue
            roof = t.size[2] - t.fill_depth
            where = self.label(i, t)
            model = tank_liquid(t).describe_tank(t).model
            if self.high[i] > roof:
                out.append(f"{where}: the free surface rose {self.high[i]:.3g} m at t = {self.t_high[i]:.4g} s, "
                           f"above the roof ({roof:.3g} m of freeboard): {model} is outside its validity")
            if self.low[i] < -t.fill_depth:
                out.append(f"{where}: the free surface fell {-self.low[i]:.3g} m at t = {self.t_low[i]:.4g} s, "
                           f"below the floor ({t.fill_depth:.3g} m deep): {model} is outside its validity")
        for i, s in enumerate(self.slope):
            # one message per tank: the breaking slope, the crests past the modes' range, or both
            t, said = self.scene.tanks[i], []
            if s > STEEP_SLOPE:
                said.append(f"the free surface's slope reached {s:.3g} at t = {self.t_slope[i]:.4g} s, steeper than "
                            f"{STEEP_SLOPE:.3g} (the 120 degree crest where waves break)")
            if not np.isnan(self.t_margin[i]):
                said.append(f"from t = {self.t_margin[i]:.4g} s its third-order system's modal mass neared "
                            f"singularity (its smallest eigenvalue over the modal masses down to {self.margin[i]:.3g}, "
                            f"below {DEFINITE_ON:.3g}): its rows were blended into the exact integrals' where it did")
            if not np.isnan(self.t_crest[i]):
                cut = self.cut.get(self.tables[i][0]) if i < len(self.tables) else None
                said.append(f"from t = {self.t_crest[i]:.4g} s its crests were higher than its modes resolve (crest "
                            f"index up to {self.crest[i]:.3g}, past {STEEP_ON:.3g}): the steep-wave damping of its "
                            f"higher modes acted from then on"
                            + (f", its modes above the {cut[0]}th as damped linear oscillators" if cut else "")
                            + ", and the results are that model's "
                            "(docs/guide/nonlinear-sloshing.md, \"Past the method's range\")")
            if said and np.isnan(self.t_crest[i]) and np.isnan(self.t_margin[i]):
                out.append(f"{self.label(i, t)}: {said[0]}: the multimodal liquid is outside its validity")
            elif said:
                out.append(f"{self.label(i, t)}: " + "; ".join(said))
        tol = self.scene.simulation.tolerance
        if self.residual > RESIDUAL_FACTOR * self.level:
            floor = "" if self.level <= tol else \
                f" and the round-off floor {self.level:.3g} of the liquid's displacement"
            out.append(f"the Newton residual reached {self.residual:.3g} at t = {self.t_residual:.4g} s, "
                       f"{self.residual / self.level:.3g} times what the iterations aim at (the tolerance {tol:.3g}"
                       f"{floor}): they stalled there, and the steps near that time are less accurate than asked "
                       f"(a smaller dt helps)")
        return out + [w for sub, *_ in self.on_bodies for w in sub.warnings()]
