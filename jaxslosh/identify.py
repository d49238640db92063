"""Parameter identification: fit scene values (dotted TOML keys) to a measured result.

    fit = js.identify(scene, "measured.h5", ["vessel.hydrostatics.gm_t", "vessel.hydrostatics.gm_l"])
    fit.values, fit.standard_errors, fit.loss_history, fit.converged

Residuals
    Weighted least squares over the channels the measured result holds and the model has: "roll"
    and "pitch" (`vessel.roll_pitch_yaw[:, :2]`), "heave" (`vessel.position[:, 2]`) and, for every
    probe present in both, "probes.<name>" (the vertical displacement `probes[name].displacement[:, 2]`).
    r = concat_c w_c (model_c(t_m) - measured_c(t_m)); the loss reported is the mean square
    SSR / n (n = number of residuals). The model runs from t = 0 with the scene's dt and
    save_every up to the last measured time; where the measured times are the model's saved times
    they are compared frame by frame, otherwise the model is interpolated (linearly) to the measured
    times (so a measured record sampled more finely or more coarsely than the model still fits).
    Default weights: w_c = 1 / std(measured_c), every channel counts as much as any other whatever
    its units; a channel with zero spread (identically zero, e.g. heave in a pure roll decay, or a
    constant) gets weight 0. `weights={"roll": 1e4, "heave": 0.0}` overrides channels by name
    (the natural choice when the noise levels are known: w_c = 1 / noise_c, and then the standard
    errors below are exact for independent Gaussian noise).

Parameters and bounds
    Each fitted key is a scalar, or a vector key (`vessel.initial.angular_velocity`, ...) fitted
    component by component; `vessel.inertia` fits the three diagonal entries (off-diagonal entries
    stay at the scene's values). The optimiser works on a transformed variable theta, so that
    bounds hold by construction (no projection, no clipping of steps):
      - default bounds: positive physical quantities (gravity, water density, mass, inertia,
        waterplane area, displaced volume, GM_T, GM_L) are bounded below by 0 and fitted in
        log: p = exp(theta), so they stay positive and steps are relative changes.
        (GM <= 0 is legal in a scene: pass bounds={"vessel.hydrostatics.gm_t": (None, None)} to
        let a GM change sign.) Initial conditions are unbounded.
      - bounds={key: (lo, hi)}: lo and hi finite: p = lo + (hi - lo) sigmoid(theta); only lo:
        p = lo + exp(theta); only hi: p = hi - exp(theta); neither: p = s theta with s = |x0|
        (1 where x0 = 0).
    The start (`x0`, default the scene's values) must lie strictly inside the bounds.

Methods (`method=`)
    "gauss-newton": Levenberg-Marquardt damped Gauss-Newton. J = d r / d theta by forward mode
        (`jax.jacfwd`, one tangent per parameter: meant for a few parameters), evaluated together
        with r in one jit-compiled function; the step solves (J^T J + lam diag(J^T J)) d = -J^T r,
        lam is divided by 10 after a step that lowers the SSR and multiplied by 10 after one that
        does not (or whose simulation failed). Converged when the relative SSR decrease is below
        1e-10, the largest step below 1e-8 in theta (a relative change of 1e-8 for a log
        parameter), or the gradient is orthogonal to the residual to 1e-8
        (|J^T r|_i / (|J_i| |r|) < 1e-8 for every i).
    "lbfgs": optax's L-BFGS direction, capped at a norm of 0.25 in theta, then its zoom line
        search, on the loss; gradients by reverse mode.
    "adam": optax.adam (learning rate `learning_rate`, default 0.02 in theta) on the loss.
    Both optax methods stop when the loss changed by less than 1e-10 relative over 5 consecutive
    iterations or the largest step in theta fell below 1e-8.

    Measured on the roll-decay problem of `notebooks/identify_metacentric_heights.ipynb` with
    scenes/vessel_only.toml (10 s record at dt 0.01, noise 1e-4 rad on roll and pitch, seed 2013,
    GM_T started 30 % high and GM_L 30 % low) on 2 CPU cores shared with other jobs (three runs;
    where they differ the range is given). "simulations" counts every evaluation of the model, the
    final one for the standard errors included; "solve" excludes compilation, which happens once
    per problem structure (its time depends on the machine's load and on what the process traced
    before):
        method          iterations  to 1 %  simulations  final loss    solve          compile
        gauss-newton         6         4          7      1.71141e-05   0.37-0.41 s    12-23 s
        lbfgs               23         3         26      1.71141e-05   1.5-2.1 s      28-39 s
        adam (lr 0.02)     288        38        289      1.71141e-05   14-35 s         7-12 s
    ("to 1 %": the first iteration after which both GMs are within 1 % of the truth.)
    All three end at the same minimum (GM_T within 0.0004 %, GM_L within 0.004 % of the truth).
    Gauss-Newton is the default: the fewest simulations and the least wall time (forward mode: r
    and the Jacobian of 2 parameters cost 0.05 s, a reverse-mode gradient 0.05-0.12 s), and its J
    gives the standard errors. On the paper's ship with its tank (scenes/paper_ship_tank.toml,
    the same record) it also takes 6 iterations (7 simulations): GM_T within 0.0002 %, GM_L within
    0.004 %. Adam with a fixed learning rate creeps to the minimum; L-BFGS is the one to use with
    many parameters (one reverse-mode gradient per evaluation whatever their number). Plain
    optax.lbfgs (no cap on the first step) went to a wrong valley on this problem (GM_L 43 m
    instead of 14.2 m, loss 0.63), hence the cap.

Standard errors
    From the Gauss-Newton covariance at the optimum in the physical parameters:
    C = sigma^2 (J_p^T J_p)^-1 with sigma^2 = SSR / (n - p) and J_p = d r / d p (also computed
    after "adam" and "lbfgs"). They assume independent residuals of equal variance after
    weighting; with the default weights (1 / std of the signal) and unequal noise levels across
    channels they are only indicative.

All model evaluations go through one jit-compiled function of the parameter vector theta and the
data (r and J together for Gauss-Newton; the whole optimiser update, line search included, for the
optax methods): the simulation is traced and compiled once, before the first iteration, never per
iteration. The compiled functions are kept for a few problem structures (scene, fitted keys and
their transforms, channels, number of samples), so a repeated fit of the same structure (another
record, start or weights) compiles nothing.
"""
from __future__ import annotations

import dataclasses
import json
import math
import os
import time as _time
from typing import Callable, Optional, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from .result import Result, load_result
from .scene_types import Scene, SceneError

METHODS = ("gauss-newton", "lbfgs", "adam")

# keys whose values are positive by nature: fitted in log by default
POSITIVE = ("environment.gravity", "environment.water_density", "vessel.mass", "vessel.inertia",
            "vessel.hydrostatics.waterplane_area", "vessel.hydrostatics.displaced_volume",
            "vessel.hydrostatics.gm_t", "vessel.hydrostatics.gm_l")

_FTOL, _XTOL, _GTOL = 1e-10, 1e-8, 1e-8
_LBFGS_MAX_STEP = 0.25

# compiled residual / Jacobian / optimiser-update functions, by problem structure (see _Problem.compiled)
_COMPILED: dict = {}
_COMPILED_MAX = 6


@dataclasses.dataclass
class FitResult:
    """The outcome of `identify`.

    values / standard_errors: key -> float (a list of floats for a vector key).
    loss_history: the loss (SSR / n of the weighted residuals) at the start and after every
    iteration. iterations: iterations done (accepted steps for Gauss-Newton, optimiser updates
    for the optax methods). evaluations: simulations run (line search and rejected
    trial steps included). channels: the weight of every channel used. wall_time: seconds in
    all; compile_time: of which tracing and compiling; solve_time: the iterations alone.
    """
    values: dict
    standard_errors: dict
    loss_history: list
    iterations: int
    converged: bool
    method: str
    message: str = ""
    evaluations: int = 0
    n_residuals: int = 0
    channels: dict = dataclasses.field(default_factory=dict)
    start: dict = dataclasses.field(default_factory=dict)
    wall_time: float = 0.0
    compile_time: float = 0.0
    solve_time: float = 0.0
    correlation: Optional[list] = None

    @property
    def loss(self) -> float:
        return self.loss_history[-1] if self.loss_history else float("nan")

    def to_dict(self) -> dict:
        return {"values": self.values, "standard_errors": self.standard_errors,
                "loss_history": [float(x) for x in self.loss_history], "iterations": int(self.iterations),
                "converged": bool(self.converged), "method": self.method}

    def to_json(self, path: Optional[str] = None, **kw) -> str:
        """The JSON text of {"values", "standard_errors", "loss_history", "iterations", "converged",
        "method"}; also written to `path` when given."""
        text = json.dumps(_json_safe(self.to_dict()), **({"indent": 2} | kw))
        if path is not None:
            with open(path, "w") as f:
                f.write(text + "\n")
        return text


def _json_safe(x):
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


# --------------------------------------------------------------------------------------------
# Parameters: keys <-> the vector theta the optimisers see


class _Param:
    """One fitted key: its slice of theta, its transform and how it goes into simulate(params=)."""

    def __init__(self, key, base, start, lo, hi):
        self.key = key
        self.base = base                              # the scene's value (np array; 3x3 for inertia)
        self.start = np.atleast_1d(np.asarray(start, dtype=float))
        self.size = self.start.size
        self.lo, self.hi = lo, hi
        self.scalar = np.ndim(start) == 0
        self.scale = np.where(self.start != 0.0, np.abs(self.start), 1.0)

    def theta_of(self, p):
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            u = (p - lo) / (hi - lo)
            return np.log(u) - np.log1p(-u)
        if lo is not None:
            return np.log(p - lo)
        if hi is not None:
            return np.log(hi - p)
        return p / self.scale

    def p_of(self, th):
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            return lo + (hi - lo) * jax.nn.sigmoid(th)
        if lo is not None:
            return lo + jnp.exp(th)
        if hi is not None:
            return hi - jnp.exp(th)
        return self.scale * th

    def dp_dtheta(self, th):
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            s = 1.0 / (1.0 + np.exp(-th))
            return (hi - lo) * s * (1 - s)
        if lo is not None:
            return np.exp(th)
        if hi is not None:
            return -np.exp(th)
        return self.scale

    def param_value(self, p):
        """The value simulate(params=) takes for this key, from the fitted components p."""
        if self.key == "vessel.inertia":
            i = np.arange(3)
            return jnp.asarray(self.base).at[i, i].set(p)
        return p[0] if self.scalar else p


def _bound_pair(key, b):
    if b is None:
        return None, None
    try:
        lo, hi = b
    except (TypeError, ValueError):
        raise SceneError(f"bounds.{key}", f"expected (lo, hi), got {b!r}")
    lo = None if lo is None or (isinstance(lo, (int, float)) and lo == -math.inf) else float(lo)
    hi = None if hi is None or (isinstance(hi, (int, float)) and hi == math.inf) else float(hi)
    if lo is not None and hi is not None and not lo < hi:
        raise SceneError(f"bounds.{key}", f"the lower bound {lo} is not below the upper bound {hi}")
    return lo, hi


def fit_keys(scene: Scene, fit: Sequence[str]) -> tuple:
    """Validate the keys to fit; SceneError naming a key that is unknown or cannot be fitted."""
    from .build import TRACEABLE
    from .scene import check_param_keys

    if isinstance(fit, str):
        fit = [fit]
    fit = list(fit)
    if not fit:
        raise SceneError("fit", "give at least one key to fit")
    keys = check_param_keys(scene, fit)
    for orig, key in zip(fit, keys):
        if key not in TRACEABLE:
            raise SceneError(orig, "cannot be fitted: the simulation cannot differentiate with respect to it "
                                   f"(fittable: {', '.join(TRACEABLE)})")
    return keys


def _make_params(scene: Scene, keys, x0, bounds) -> list:
    from .scene import canonical_key, scene_values

    values = scene_values(scene)
    x0 = {canonical_key(scene, k): v for k, v in (x0 or {}).items()}
    bounds = {canonical_key(scene, k): v for k, v in (bounds or {}).items()}
    for k in list(x0) + list(bounds):
        if k not in keys:
            raise SceneError(k, f"given in x0 or bounds but not fitted (fitted: {', '.join(keys)})")
    out = []
    for key in keys:
        base = np.asarray(values[key], dtype=float)
        default = np.diag(base) if key == "vessel.inertia" else base
        start = np.asarray(x0.get(key, default), dtype=float)
        if start.shape != default.shape:
            raise SceneError(f"x0.{key}", f"expected shape {default.shape}, got {start.shape}")
        if key in bounds:
            lo, hi = _bound_pair(key, bounds[key])
        else:
            lo, hi = (0.0, None) if key in POSITIVE else (None, None)
        if not np.all(np.isfinite(start)):
            raise SceneError(f"x0.{key}", "the start must be finite")
        if (lo is not None and np.any(start <= lo)) or (hi is not None and np.any(start >= hi)):
            why = "; the value must stay positive" if key in POSITIVE and key not in bounds else ""
            raise SceneError(key, f"the start {start.tolist()} is not strictly inside the bounds ({lo}, {hi}){why}")
        out.append(_Param(key, base, start, lo, hi))
    return out


# --------------------------------------------------------------------------------------------
# Channels and the residual


def _as_result(measured) -> Result:
    if isinstance(measured, Result):
        return measured
    if isinstance(measured, (str, os.PathLike)):
        return load_result(os.fspath(measured))
    raise TypeError(f"measured: expected a Result or the path of a result file, got {type(measured).__name__}")


def channels_of(r: Result, names=None) -> dict:
    """name -> (n,) signal of a result: roll, pitch, heave and probes.<name> (vertical displacement)."""
    rpy = r.vessel.roll_pitch_yaw
    ch = {"roll": rpy[:, 0], "pitch": rpy[:, 1], "heave": r.vessel.position[:, 2]}
    for name, p in r.probes.items():
        ch[f"probes.{name}"] = p.displacement[:, 2]
    if names is not None:
        ch = {k: ch[k] for k in names}
    return ch


def add_noise(r: Result, noise: dict, seed: int = 0, keep_probes: bool = True) -> Result:
    """A synthetic measurement: `r` with independent Gaussian noise of standard deviation
    noise[channel] added to the channels `identify` reads ("roll", "pitch", "heave",
    "probes.<name>"); other datasets (quaternion, probe positions, ...) are left as they are.
    keep_probes=False drops the probes (a record of the vessel's motion alone)."""
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
    return dataclasses.replace(r, vessel=vessel, probes=probes)


class _Problem:
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
        model_names = {"roll", "pitch", "heave"} | {f"probes.{p.name}" for p in scene.probes}
        names = [k for k in meas if k in model_names]
        weights = dict(weights or {})
        for k in weights:
            if k not in names:
                raise SceneError(f"weights.{k}", f"no such channel in both the measurement and the model "
                                                 f"(channels: {', '.join(names)})")
        self.weights = {}
        for k in names:
            x = meas[k]
            if not np.all(np.isfinite(x)):
                raise SceneError("measured", f"channel {k} holds non-finite values")
            if k in weights:
                w = float(weights[k])
                if not (w >= 0 and math.isfinite(w)):
                    raise SceneError(f"weights.{k}", f"must be finite and >= 0, got {weights[k]}")
            else:
                s = float(np.std(x))
                w = 1.0 / s if s > 1e-300 and s > 1e-12 * float(np.max(np.abs(x))) else 0.0
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
        from .run import simulate
        # traced under jit: what does not depend on theta (the host-side assembly of the liquid
        # matrices, in NumPy) is evaluated while tracing, as it would be outside jit
        with jax.ensure_compile_time_eval():
            return simulate(self.scene, params=self.sim_params(theta), duration=self.duration)

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
        ok = jnp.all(jnp.isfinite(res)) & (jnp.max(r.solver.residual) <= 100.0 * self.tol)
        return res, ok

    def _residual_jac(self, theta, data):
        def f(th):
            res, ok = self._residual_ok(th, data)
            return res, (res, ok)
        J, (res, ok) = jax.jacfwd(f, has_aux=True)(theta)
        return res, J, ok

    def _loss(self, theta, data):
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


# --------------------------------------------------------------------------------------------
# Optimisers


def _gauss_newton(pb: _Problem, theta, max_iter, callback, history):
    res, J, ok = pb.residual_jacobian(theta)
    last = (res, J, ok)
    if not ok:
        return theta, 0, False, "the simulation at the start failed (Newton not converged or non-finite values)", last
    ssr = float(res @ res)
    history.append(ssr / pb.n)
    lam = 1e-3
    it, converged, message = 0, False, f"stopped after max_iter = {max_iter} iterations"
    while it < max_iter:
        g = J.T @ res
        A = J.T @ J
        d = np.maximum(np.diag(A), 1e-12 * max(1.0, float(np.max(np.diag(A)))))
        colnorm = np.sqrt(np.diag(A))
        if np.all(np.abs(g) <= _GTOL * np.maximum(colnorm, 1e-300) * math.sqrt(ssr)) or ssr == 0.0:
            converged, message = True, "gradient orthogonal to the residual"
            break
        accepted, any_ok = False, False
        for _ in range(12):
            try:
                step = np.linalg.solve(A + lam * np.diag(d), -g)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            t_new = theta + step
            r_new, J_new, ok_new = pb.residual_jacobian(t_new)
            ssr_new = float(r_new @ r_new) if ok_new else math.inf
            any_ok = any_ok or ok_new
            if ssr_new < ssr:
                accepted = True
                break
            lam *= 10.0
        if not accepted:
            if any_ok:      # no damping lowers the SSR: a minimum to round-off
                converged, message = True, "no step lowers the loss (a minimum to round-off)"
            else:
                message = "every trial step failed to simulate (Newton did not converge or non-finite values)"
            break
        it += 1
        rel = (ssr - ssr_new) / ssr
        theta, res, J, ssr = t_new, r_new, J_new, ssr_new
        last = (res, J, True)
        lam = max(lam / 10.0, 1e-12)
        history.append(ssr / pb.n)
        if callback is not None and callback(it, pb.values(theta), ssr / pb.n):
            message = "stopped by the callback"
            break
        if rel < _FTOL:
            converged, message = True, f"relative loss decrease {rel:.2g} < {_FTOL:g}"
            break
        if np.max(np.abs(step)) < _XTOL:
            converged, message = True, f"step {np.max(np.abs(step)):.2g} < {_XTOL:g}"
            break
    return theta, it, converged, message, last


def _optax_loop(pb: _Problem, theta, method, max_iter, callback, history, learning_rate):
    import optax

    theta = jnp.asarray(theta)
    if method == "adam":
        lr = learning_rate if learning_rate is not None else 0.02
        opt = optax.adam(lr)

        def update(th, state, data):
            value, grad = jax.value_and_grad(pb._loss)(th, data)
            upd, state = opt.update(grad, state, th)
            return optax.apply_updates(th, upd), state, value, 1
    else:
        # optax.lbfgs, with the quasi-Newton direction capped at _LBFGS_MAX_STEP in theta before the
        # line search (which may still lengthen it): without the cap the first step (a unit ball in
        # theta) jumps into the wrong valley of an oscillation fit (GM_L 30 % low -> 3 x too high)
        opt = optax.chain(optax.scale_by_lbfgs(), optax.clip_by_global_norm(_LBFGS_MAX_STEP),
                          optax.scale(-1.0) if learning_rate is None else optax.scale_by_learning_rate(learning_rate),
                          optax.scale_by_zoom_linesearch(max_linesearch_steps=20))
        lr = learning_rate

        def update(th, state, data):
            loss = lambda x: pb._loss(x, data)  # noqa: E731
            value, grad = optax.value_and_grad_from_state(loss)(th, state=state)
            upd, state = opt.update(grad, state, th, value=value, grad=grad, value_fn=loss)
            n_ls = optax.tree_utils.tree_get(state, "info").num_linesearch_steps
            return optax.apply_updates(th, upd), state, value, n_ls

    state = opt.init(theta)
    update = pb.compiled((method, lr), update, theta, state, pb.data)
    it, converged, message, flat = 0, False, f"stopped after max_iter = {max_iter} iterations", 0
    final_known = False          # whether history[-1] is the loss at the returned theta
    while it < max_iter:
        t_new, state, value, n_eval = update(theta, state, pb.data)
        value = float(value)      # the loss at theta (before this update)
        pb.evaluations += int(n_eval) if method == "lbfgs" else 1
        history.append(value)
        final_known = True
        if len(history) == 1:
            if not math.isfinite(value):
                return np.asarray(theta), 0, False, "the simulation at the start failed", True
        else:
            prev = history[-2]
            flat = flat + 1 if abs(prev - value) <= _FTOL * max(abs(prev), 1e-300) else 0
            if callback is not None and callback(it, pb.values(theta), value):
                message = "stopped by the callback"
                break
            if flat >= 5:
                converged, message = True, f"loss changed by < {_FTOL:g} relative over 5 iterations"
                break
        if not bool(jnp.all(jnp.isfinite(t_new))):
            message = "the optimiser produced non-finite parameters"
            break
        step = float(jnp.max(jnp.abs(t_new - theta)))
        theta = t_new
        final_known = False
        it += 1
        if step < _XTOL:
            converged, message = True, f"step {step:.2g} < {_XTOL:g}"
            break
    return np.asarray(theta), it, converged, message, final_known


def identify(scene: Scene, measured, fit: Sequence[str], *, weights: Optional[dict] = None,
             method: str = "gauss-newton", max_iter: int = 50, x0: Optional[dict] = None,
             bounds: Optional[dict] = None, callback: Optional[Callable] = None,
             learning_rate: Optional[float] = None) -> FitResult:
    """Fit the scene values named by `fit` (dotted keys) to `measured` (a Result or a result file).

    weights: channel -> weight ("roll", "pitch", "heave", "probes.<name>"), default 1 / std of the
    measured channel (0 for a constant channel). method: "gauss-newton" (default), "lbfgs" or
    "adam". x0: key -> start value (default the scene's). bounds: key -> (lo, hi), None for an open
    side (default: (0, None) for positive quantities, fitted in log). callback(iteration, values,
    loss) after every iteration; returning True stops the fit. Raises SceneError (naming the key)
    for bad input. See the module docstring for the details.
    """
    if method not in METHODS:
        raise SceneError("method", f"unknown method {method!r} (choose from {', '.join(METHODS)})")
    if int(max_iter) < 0:
        raise SceneError("max_iter", f"must be >= 0, got {max_iter}")
    t0 = _time.perf_counter()
    measured = _as_result(measured)
    keys = fit_keys(scene, fit)
    params = _make_params(scene, keys, x0, bounds)
    pb = _Problem(scene, measured, params, weights)
    history: list = []
    t_solve = _time.perf_counter()
    if method == "gauss-newton":
        theta, it, converged, message, last = _gauss_newton(pb, pb.theta0.copy(), int(max_iter), callback, history)
        final_known = True
    else:
        theta, it, converged, message, final_known = _optax_loop(pb, pb.theta0.copy(), method, int(max_iter),
                                                                 callback, history, learning_rate)
    solve_time = _time.perf_counter() - t_solve - pb.compile_time
    # standard errors from the Gauss-Newton covariance, in the physical parameters
    res, J, ok = last if method == "gauss-newton" else pb.residual_jacobian(theta)
    p_dim = J.shape[1]
    se_vec = np.full(p_dim, np.nan)
    corr = None
    if ok and pb.n > p_dim:
        Jp = J / pb.dp_dtheta(theta)[None, :]
        s2 = float(res @ res) / (pb.n - p_dim)
        A = Jp.T @ Jp
        try:
            cov = s2 * np.linalg.inv(A)
            if np.all(np.isfinite(cov)) and np.all(np.diag(cov) >= 0):
                se_vec = np.sqrt(np.diag(cov))
                dd = np.sqrt(np.diag(cov))
                corr = (cov / np.outer(dd, dd)).tolist() if np.all(dd > 0) else None
        except np.linalg.LinAlgError:
            pass
    se = {}
    for p, a, b in zip(params, pb.offsets[:-1], pb.offsets[1:]):
        se[p.key] = float(se_vec[a]) if p.scalar else [float(x) for x in se_vec[a:b]]
    if not final_known:
        history.append(float(res @ res) / pb.n if ok else math.inf)   # the loss at the returned parameters
    start = {p.key: (float(p.start[0]) if p.scalar else p.start.tolist()) for p in params}
    return FitResult(values=pb.values(theta), standard_errors=se, loss_history=[float(x) for x in history],
                     iterations=int(it), converged=bool(converged), method=method, message=message,
                     evaluations=pb.evaluations, n_residuals=pb.n, channels=dict(pb.weights), start=start,
                     wall_time=_time.perf_counter() - t0, compile_time=pb.compile_time, solve_time=solve_time,
                     correlation=corr)


# --------------------------------------------------------------------------------------------
# A figure


def plot_fit(scene: Scene, measured, fit_result: FitResult, out_png: Optional[str] = None, *, start: bool = True):
    """Measured against fitted time histories, one panel per channel that carries weight (and the
    start's history, dashed, when `start`). Writes `out_png` when given; returns the figure."""
    from .run import simulate

    measured = _as_result(measured)
    t_m = np.asarray(measured.time)
    T = float(t_m[-1])
    meas = {k: np.asarray(v) for k, v in channels_of(measured).items()}
    names = [k for k, w in fit_result.channels.items() if w > 0] or [
        k for k in ("roll", "pitch", "heave") if np.std(meas[k]) > 0]
    params_of = lambda vals: {k: _param_for(scene, k, v) for k, v in vals.items()}  # noqa: E731
    fitted = simulate(scene, params=params_of(fit_result.values), duration=max(T, scene.simulation.dt))
    ch_fit = {k: np.asarray(v) for k, v in channels_of(fitted).items()}
    ch_start = None
    if start and fit_result.start:
        r0 = simulate(scene, params=params_of(fit_result.start), duration=max(T, scene.simulation.dt))
        ch_start = {k: np.asarray(v) for k, v in channels_of(r0).items()}
    t_f = np.asarray(fitted.time)

    if out_png is None:
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(len(names), 1, figsize=(9, 2.4 * len(names) + 0.6), sharex=True, squeeze=False)
    else:
        from matplotlib.figure import Figure
        fig = Figure(figsize=(9, 2.4 * len(names) + 0.6))
        axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)
    units = {"roll": ("deg", np.degrees), "pitch": ("deg", np.degrees), "heave": ("m", lambda x: x)}
    for ax, k in zip(axes[:, 0], names):
        unit, conv = units.get(k, ("m", lambda x: x))
        ax.plot(t_m, conv(meas[k]), ".", ms=3, color="k", alpha=0.35, label="measured")
        if ch_start is not None and k in ch_start:
            ax.plot(np.asarray(r0.time), conv(ch_start[k]), "--", lw=0.9, color="C1", label="start")
        if k in ch_fit:
            ax.plot(t_f, conv(ch_fit[k]), "-", lw=1.0, color="C0", label="fitted")
        ax.set_ylabel(f"{k} ({unit})")
        ax.legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    vals = ", ".join(f"{k.split('.')[-1]} = {_fmt(v)}" for k, v in fit_result.values.items())
    fig.suptitle(f"identify ({fit_result.method}, {fit_result.iterations} iterations): {vals}", fontsize=9)
    fig.tight_layout()
    if out_png is not None:
        fig.savefig(out_png, dpi=110)
    return fig


def _fmt(v):
    return f"{v:.5g}" if isinstance(v, float) else "[" + ", ".join(f"{x:.5g}" for x in v) + "]"


def _param_for(scene: Scene, key: str, value):
    if key == "vessel.inertia":
        from .scene import scene_values
        base = np.array(scene_values(scene)[key], dtype=float)
        base[np.arange(3), np.arange(3)] = value
        return base
    return np.asarray(value, dtype=float) if isinstance(value, list) else float(value)


# --------------------------------------------------------------------------------------------
# The command line: `jaxslosh identify SCENE --data MEASURED.h5 --fit KEY[,KEY...] [-o FIT.json]`


def add_identify_parser(subparsers):
    """Add the `identify` subcommand to the `jaxslosh` sub-parsers; returns its parser."""
    p = subparsers.add_parser("identify", help="fit scene values (dotted keys) to a measured result")
    p.add_argument("scene")
    p.add_argument("--data", required=True, metavar="MEASURED.h5", help="the measured result file")
    p.add_argument("--fit", required=True, metavar="KEY[,KEY...]",
                   help="dotted scene keys to fit, comma-separated, e.g. "
                        "vessel.hydrostatics.gm_t,vessel.hydrostatics.gm_l")
    p.add_argument("-o", "--output", metavar="FIT.json",
                   help="the fit as JSON (default: the scene's name with _fit.json, here)")
    p.add_argument("--method", default="gauss-newton", choices=METHODS, help="optimiser (default gauss-newton)")
    p.add_argument("--max-iter", type=int, default=50, dest="max_iter", help="iterations at most (default 50)")
    p.add_argument("--start", metavar="KEY=VALUE[,...]", help="start values (default: the scene's values)")
    p.add_argument("--plot", metavar="FIG.png", help="also draw measured against fitted time histories")
    return p


def _split_keys(text):
    return [k.strip() for k in str(text).split(",") if k.strip()]


def cmd_identify(a) -> int:
    """`jaxslosh identify`: returns the exit status; bad input raises jaxslosh.cli.InputError."""
    import sys

    from .cli import EXIT_NUMERICAL, EXIT_OK, InputError

    method = getattr(a, "method", None) or "gauss-newton"
    if method not in METHODS:
        raise InputError(f"--method: unknown method {method!r} (choose from {', '.join(METHODS)})")
    max_iter = getattr(a, "max_iter", None)
    max_iter = 50 if max_iter is None else int(max_iter)
    if max_iter < 0:
        raise InputError(f"--max-iter: must be >= 0, got {max_iter}")
    keys = _split_keys(a.fit or "")
    if not keys:
        raise InputError("--fit: give at least one dotted key, e.g. vessel.hydrostatics.gm_t")
    if not os.path.exists(a.scene):
        raise InputError(f"{a.scene}: no such scene file")
    if not a.data or not os.path.exists(a.data):
        raise InputError(f"--data: {a.data}: no such file")
    out = getattr(a, "output", None) or os.path.splitext(os.path.basename(a.scene))[0] + "_fit.json"
    for flag, path in (("-o", out), ("--plot", getattr(a, "plot", None))):
        if path:
            d = os.path.dirname(os.path.abspath(path))
            if not os.path.isdir(d):
                raise InputError(f"{flag}: the folder {d} does not exist")
    x0 = {}
    for item in _split_keys(getattr(a, "start", None) or ""):
        k, sep, v = item.partition("=")
        try:
            x0[k.strip()] = float(v)
        except ValueError:
            raise InputError(f"--start: expected KEY=VALUE, got {item!r}")
        if not sep:
            raise InputError(f"--start: expected KEY=VALUE, got {item!r}")

    import jax as _jax
    _jax.config.update("jax_enable_x64", True)
    from .scene import load_scene
    scene = load_scene(a.scene)            # SceneError (exit 2, naming the key) for a bad scene
    for w in scene.warnings:
        print(f"warning: {w}", file=sys.stderr)
    try:
        fit_keys(scene, keys)
    except SceneError as e:
        raise InputError(f"--fit: {e}")
    try:
        measured = load_result(a.data)
    except (OSError, ValueError, KeyError) as e:
        msg = str(e).replace("\n", " ")
        raise InputError(f"--data: {a.data}: not a jaxslosh result file ({msg})")
    try:
        fr = identify(scene, measured, keys, method=method, max_iter=max_iter, x0=x0 or None)
    except SceneError as e:
        msg = str(e).replace("\n", " ")
        flag = "--start" if ("the start" in msg or "given in x0" in msg) else "--data" if e.key == "measured" else None
        raise InputError(f"{flag}: {msg}" if flag else msg)
    if not fr.loss_history or not math.isfinite(fr.loss_history[0]):
        print(f"jaxslosh identify: numerical failure: {fr.message}", file=sys.stderr)
        return EXIT_NUMERICAL
    width = max(len(k) for k in fr.values)
    for k, v in fr.values.items():
        s = fr.standard_errors[k]
        print(f"{k:<{width}} = {_fmt(v)} +- {_fmt(s)}   (start {_fmt(fr.start[k])})")
    status = "converged" if fr.converged else "NOT converged"
    print(f"{fr.method}: {status} after {fr.iterations} iterations ({fr.evaluations} simulations, "
          f"{fr.wall_time:.1f} s); loss {fr.loss_history[0]:.4g} -> {fr.loss_history[-1]:.4g} ({fr.message})")
    fr.to_json(out)
    print(f"wrote {out}")
    if getattr(a, "plot", None):
        plot_fit(scene, measured, fr, a.plot)
        print(f"wrote {a.plot}")
    if not fr.converged:
        print(f"warning: the fit did not converge ({fr.message})", file=sys.stderr)
    return EXIT_OK
