"""The residual of one identification, compiled once: the model's channels against the measured
ones, weighted."""
from __future__ import annotations

import dataclasses
import math
import os
import time as _time
from typing import Optional

import jax
import jax.numpy as jnp
import numpy as np

from ..io.result import Result, load_result
from ..run.simulate import simulate
from ..scene.types import Scene, SceneError


# compiled residual / Jacobian / optimiser-update functions, by problem structure (see _Problem.compiled)
_COMPILED: dict = {}


_COMPILED_MAX = 6


def as_result(measured) -> Result:
    if isinstance(measured, Result):
        return measured
    if isinstance(measured, (str, os.PathLike)):
        return load_result(os.fspath(measured))
    raise TypeError(f"measured: expected a Result or the path of a result file, got {type(measured).__name__}")


def channels_of(r: Result, names=None) -> dict:
    """name -> (n,) signal of a result: roll, pitch, heave, probes.<name> (vertical displacement),
    bodies.<name>.roll, .pitch, .heave (a [[bodies]] body's; its heave: its COG's offset from rest)
    and connections.<name> (a connection's force, N)."""
    rpy = r.vessel.roll_pitch_yaw
    ch = {"roll": rpy[:, 0], "pitch": rpy[:, 1], "heave": r.vessel.position[:, 2]}
    for name, p in r.probes.items():
        ch[f"probes.{name}"] = p.displacement[:, 2]
    for name, b in (r.bodies or {}).items():
        ch |= {f"bodies.{name}.roll": b.roll_pitch_yaw[:, 0], f"bodies.{name}.pitch": b.roll_pitch_yaw[:, 1],
               f"bodies.{name}.heave": b.position[:, 2]}
    for name, c in (r.connections or {}).items():
        ch[f"connections.{name}"] = c.force
    if names is not None:
        ch = {k: ch[k] for k in names}
    return ch


def add_noise(r: Result, noise: dict, seed: int = 0, keep_probes: bool = True) -> Result:
    """A synthetic measurement: `r` with independent Gaussian noise of standard deviation
    noise[channel] added to the channels `identify` reads ("roll", "pitch", "heave",
    "probes.<name>", "bodies.<name>.roll", ..., "connections.<name>"); other datasets (quaternion,
    probe positions, ...) are left as they are. keep_probes=False drops the probes (a record of
    the vessel's motion alone)."""
    rng = np.random.default_rng(seed)
    names = set(channels_of(r))
    for k in noise:
        if k not in names:
            raise SceneError(f"noise.{k}", f"no such channel (channels: {', '.join(sorted(names))})")
    n = len(np.asarray(r.time))
    draw = lambda k: noise.get(k, 0.0) * rng.standard_normal(n)  # noqa: E731
    rpy = np.array(r.vessel.roll_pitch_yaw, dtype=float)
    rpy[:, 0] += draw("roll")
    rpy[:, 1] += draw("pitch")
    pos = np.array(r.vessel.position, dtype=float)
    pos[:, 2] += draw("heave")
    probes = {}
    if keep_probes:
        for name, p in r.probes.items():
            d = np.array(p.displacement, dtype=float)
            d[:, 2] += draw(f"probes.{name}")
            probes[name] = dataclasses.replace(p, displacement=d)
    vessel = dataclasses.replace(r.vessel, roll_pitch_yaw=rpy, position=pos)
    bodies = {}
    for name, b in (r.bodies or {}).items():     # drawn after the vessel's and the probes': their noise as before
        brpy, bpos = np.array(b.roll_pitch_yaw, dtype=float), np.array(b.position, dtype=float)
        brpy[:, 0] += draw(f"bodies.{name}.roll")
        brpy[:, 1] += draw(f"bodies.{name}.pitch")
        bpos[:, 2] += draw(f"bodies.{name}.heave")
        bodies[name] = dataclasses.replace(b, roll_pitch_yaw=brpy, position=bpos)
    links = {name: dataclasses.replace(c, force=np.asarray(c.force, dtype=float) + draw(f"connections.{name}"))
             for name, c in (r.connections or {}).items()}
    return dataclasses.replace(r, vessel=vessel, probes=probes, bodies=bodies or r.bodies,
                               connections=links or r.connections)


#: a channel whose spread is at most this share of the largest spread among the channels in its unit
#: is round-off of a motion the record does not hold (the pitch of a pure roll decay, 1e-17 rad):
#: by default it gets weight 0, since 1 / std would make that round-off outweigh every signal
ROUNDOFF = 1e-9
#: ... and so is a spread below this in the channel's unit (rad, m): no record resolves it
SIGNAL_FLOOR = 1e-10


def channel_unit(name: str) -> str:
    """rad (roll, pitch, a body's), N (a connection's force) or m."""
    if name.startswith("connections."):
        return "N"
    return "rad" if name in ("roll", "pitch") or (name.startswith("bodies.") and name.endswith((".roll", ".pitch"))) \
        else "m"


def no_signal(name: str, x, spread: dict) -> bool:
    """Whether a measured channel holds nothing to fit (weight 0 by default): a constant (its spread
    round-off of its own level), a spread below SIGNAL_FLOOR, or one at round-off (ROUNDOFF) of the
    largest spread among the channels measured in its unit."""
    s = spread[name]
    same = max(v for k, v in spread.items() if channel_unit(k) == channel_unit(name))
    return not (s > 1e-12 * float(np.max(np.abs(x))) and s >= SIGNAL_FLOOR and s > ROUNDOFF * same)


class Problem:
    """The residual r(theta) of one identification, compiled once."""

    def __init__(self, scene: Scene, measured: Result, params: list, weights: Optional[dict]):
        self.scene, self.params = scene, params
        sim = scene.simulation
        t = np.asarray(measured.time, dtype=float)
        if t.ndim != 1 or t.size < 2:
            raise SceneError("measured", "the measured result holds fewer than 2 frames")
        if t[0] < -1e-9 or np.any(np.diff(t) <= 0):
            raise SceneError("measured", "the measured times must start at t >= 0 and increase")
        grid = sim.dt * max(1, int(sim.save_every))
        n_frames = max(1, int(math.ceil(t[-1] / grid - 1e-9)))
        self.duration = n_frames * grid
        t_model = np.arange(n_frames + 1) * grid
        self.t_measured, self.t_model = t, t_model
        # frame by frame where the measured times are the model's saved times
        self.direct = t.size <= t_model.size and np.allclose(t, t_model[:t.size], rtol=0.0, atol=1e-9 * max(1.0, t[-1]))

        meas = {k: np.asarray(v, dtype=float) for k, v in channels_of(measured).items()}
        model_names = ({"roll", "pitch", "heave"} | {f"probes.{p.name}" for p in scene.probes}
                       | {f"bodies.{b.name}.{c}" for b in scene.bodies for c in ("roll", "pitch", "heave")}
                       | {f"connections.{c.name}" for c in scene.connections})
        names = [k for k in meas if k in model_names]
        weights = dict(weights or {})
        for k in weights:
            if k not in names:
                raise SceneError(f"weights.{k}", f"no such channel in both the measurement and the model "
                                                 f"(channels: {', '.join(names)})")
        self.weights = {}
        for k in names:
            if not np.all(np.isfinite(meas[k])):
                raise SceneError("measured", f"channel {k} holds non-finite values")
        spread = {k: float(np.std(meas[k])) for k in names}
        self.no_signal = {k: spread[k] for k in names if k not in weights and no_signal(k, meas[k], spread)}
        for k in names:
            if k in weights:
                w = float(weights[k])
                if not (w >= 0 and math.isfinite(w)):
                    raise SceneError(f"weights.{k}", f"must be finite and >= 0, got {weights[k]}")
            else:
                w = 0.0 if k in self.no_signal else 1.0 / spread[k]
            self.weights[k] = w
        self.active = [k for k in names if self.weights[k] > 0]
        if not self.active:
            raise SceneError("measured", "no channel to fit: every measured channel is constant or has weight 0 "
                                         f"(channels: {', '.join(names) or 'none'})")
        # the data, an argument of the compiled functions (so that they serve any record of this shape)
        self.data = (jnp.asarray(t), jnp.asarray(np.stack([meas[k] for k in self.active])),
                     jnp.asarray([self.weights[k] for k in self.active]))
        self.n = t.size * len(self.active)
        sizes = [p.size for p in params]
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
        self.theta0 = np.concatenate([p.theta_of(p.start) for p in params])
        self.tol = float(sim.tolerance)
        self._rj = None
        self.evaluations = 0
        self.compile_time = 0.0
        self.key = (dataclasses.replace(scene, path="", warnings=()),
                    tuple((p.key, p.lo, p.hi, tuple(p.scale.tolist()) if p.lo is None and p.hi is None else None,
                           p.base.tobytes(), p.size, p.scalar)
                          for p in params),
                    self.duration, bool(self.direct), tuple(self.active), t.size)

    def compiled(self, name, fn, *args):
        """`fn` jit-compiled ahead of time for arguments like `args`, so that compiling is timed apart
        from the iterations. Kept (a few, least recently used out) under `name` and the problem's
        structure: the scene, the fitted keys and their transforms, the channels and the number of
        samples; a later identify of the same structure (another record, start, weights) reuses it."""
        key = (name, self.key)
        try:
            hit = _COMPILED.pop(key, None)
        except TypeError:                       # an unhashable scene: no reuse
            key, hit = None, None
        if hit is None:
            t0 = _time.perf_counter()
            hit = jax.jit(fn).lower(*args).compile()
            self.compile_time += _time.perf_counter() - t0
        if key is not None:
            _COMPILED[key] = hit
            while len(_COMPILED) > _COMPILED_MAX:
                _COMPILED.pop(next(iter(_COMPILED)))
        return hit

    # the model -------------------------------------------------------------------------------
    def physical(self, theta):
        return [p.p_of(theta[a:b]) for p, a, b in zip(self.params, self.offsets[:-1], self.offsets[1:])]

    def sim_params(self, theta) -> dict:
        return {p.key: p.param_value(v) for p, v in zip(self.params, self.physical(theta))}

    def simulate(self, theta):
        # traced under jit: what does not depend on theta (the host-side assembly of the liquid
        # matrices, in NumPy) is evaluated while tracing, as it would be outside jit
        with jax.ensure_compile_time_eval():
            # a failed run is a point the fit steps back from (`ok` below), not an error
            return simulate(self.scene, params=self.sim_params(theta), duration=self.duration, throw=False)

    def model_channels(self, r: Result, t_measured) -> dict:
        ch = channels_of(r, self.active)
        if self.direct:
            return {k: v[:self.t_measured.size] for k, v in ch.items()}
        return {k: jnp.interp(t_measured, r.time, v) for k, v in ch.items()}

    # traced: functions of theta and the data (t_measured, measured (channels, n), weights (channels,))
    def _residual_ok(self, theta, data):
        t_measured, meas, w = data
        r = self.simulate(theta)
        ch = self.model_channels(r, t_measured)
        model = jnp.stack([ch[k] for k in self.active])
        res = (w[:, None] * (model - meas)).reshape(-1)
        ok = r.ok & jnp.all(jnp.isfinite(res)) & (jnp.max(r.solver.residual) <= 100.0 * self.tol)
        return res, ok

    def _residual_jac(self, theta, data):
        def f(th):
            res, ok = self._residual_ok(th, data)
            return res, (res, ok)
        J, (res, ok) = jax.jacfwd(f, has_aux=True)(theta)
        return res, J, ok

    def loss(self, theta, data):
        res, ok = self._residual_ok(theta, data)
        return jnp.where(ok, jnp.mean(res ** 2), jnp.inf)

    # evaluations counted, results on the host -------------------------------------------------
    def residual_jacobian(self, theta):
        self.evaluations += 1
        if self._rj is None:
            self._rj = self.compiled("jacobian", self._residual_jac, jnp.asarray(self.theta0), self.data)
        res, J, ok = self._rj(jnp.asarray(theta), self.data)
        return np.asarray(res), np.asarray(J), bool(ok)

    def values(self, theta) -> dict:
        out = {}
        for p, v in zip(self.params, self.physical(jnp.asarray(theta))):
            v = np.asarray(v, dtype=float)
            out[p.key] = float(v[0]) if p.scalar else [float(x) for x in v]
        return out

    def dp_dtheta(self, theta):
        return np.concatenate([p.dp_dtheta(np.asarray(theta[a:b]))
                               * np.ones(p.size) for p, a, b in zip(self.params, self.offsets[:-1], self.offsets[1:])])
