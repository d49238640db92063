"""Parameter identification: fit scene values (dotted TOML keys) to a measured result.

    fit = js.identify(scene, "measured.h5", ["vessel.hydrostatics.gm_t", "vessel.hydrostatics.gm_l"])
    fit.values, fit.standard_errors, fit.loss_history, fit.converged

Residuals
    Weighted least squares over the channels the measured result holds and the model has: "roll"
    and "pitch" (`vessel.roll_pitch_yaw[:, :2]`), "heave" (`vessel.position[:, 2]`) and, for every
    probe present in both, "probes.<name>" (the vertical displacement `probes[name].displacement[:, 2]`);
    "bodies.<name>.roll", ".pitch", ".heave" of each [[bodies]] body and "connections.<name>" (a
    connection's force) of each [[connections]] connection.
    r = concat_c w_c (model_c(t_m) - measured_c(t_m)); the loss reported is the mean square
    SSR / n (n = number of residuals). The model runs from t = 0 with the scene's dt and
    save_every up to the last measured time; where the measured times are the model's saved times
    they are compared frame by frame, otherwise the model is interpolated (linearly) to the measured
    times (so a measured record sampled more finely or more coarsely than the model still fits).
    Default weights: w_c = 1 / std(measured_c), every channel counts as much as any other whatever
    its units; a channel without signal gets weight 0 (`no_signal`): zero spread (identically zero,
    e.g. heave in a pure roll decay, or a constant), or a spread at round-off, below 1e-9 of the
    largest among the channels in its unit or below 1e-10 rad (m) (the pitch of a roll decay, 1e-17
    rad, whose 1 / std would make its round-off outweigh the roll and bias the fit).
    `weights={"roll": 1e4, "heave": 0.0}` overrides channels by name
    (the natural choice when the noise levels are known: w_c = 1 / noise_c, and then the standard
    errors below are exact for independent Gaussian noise).

Parameters and bounds
    Each fitted key is a scalar, or a vector key (`vessel.initial.angular_velocity`, ...) fitted
    component by component; `vessel.inertia` fits the three diagonal entries (off-diagonal entries
    stay at the scene's values). The optimiser works on a transformed variable theta, so that
    bounds hold by construction (no projection, no clipping of steps):
      - default bounds: positive physical quantities (gravity, water density, mass, inertia,
        waterplane area, displaced volume, GM_T, GM_L, KG) are bounded below by 0 and fitted in
        log: p = exp(theta), so they stay positive and steps are relative changes.
        (GM <= 0 is legal in a scene: pass bounds={"vessel.hydrostatics.gm_t": (None, None)} to
        let a GM change sign.) Initial conditions are unbounded.
      - bounds={key: (lo, hi)}: lo and hi finite: p = lo + (hi - lo) sigmoid(theta); only lo:
        p = lo + exp(theta); only hi: p = hi - exp(theta); neither: p = s theta with s = |x0|
        (1 where x0 = 0).
    The start (`x0`, default the scene's values) must lie strictly inside the bounds.

KG and GM0 with the nonlinear hydrostatics
    `vessel.hull.kg` (a box hull, `model = "nonlinear"`) moves the COG against the hull: the
    restoring of the instantaneous wetted surface follows, over the whole GZ curve, from one
    number. GM0 is then not a parameter of its own: the fit reports the implied GM0 = KM - KG of
    the hull at rest (`implied`), and fitting the springs' values (GM_T, GM_L, A_w, V), which the
    nonlinear model does not read, is refused naming the key. With the linear model KG cannot be
    traced (the springs were derived from it when the scene was loaded): fit GM_T there. A mesh
    hull's analogue is `vessel.hull.cog` (the COG in the file's coordinates).

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

Standard errors
    From the Gauss-Newton covariance at the optimum in the physical parameters:
    C = sigma^2 (J_p^T J_p)^-1 with sigma^2 = SSR / (n - p) and J_p = d r / d p (also computed
    after "adam" and "lbfgs"). They assume independent residuals of equal variance after
    weighting; with the default weights (1 / std of the signal) and unequal noise levels across
    channels they are only indicative.

The data's scene and the quality of the fit (quality.py)
    When the measured result carries the scene that made it (result files do), every value and
    every part of the structure that differs from `scene`, apart from the fitted keys and harmless
    ones (the duration, the solver's settings), is named: `data_scene="warn"` (default) warns,
    "error" raises SceneError, "ignore" says nothing. After the fit, R^2 per channel and the
    residual against the noise estimated from the record; a channel with R^2 < 0.9 whose residual
    is more than 3 times that noise makes the fit poor (`quality`: "poor fit: R^2 0.12 on roll"):
    the model, not the noise, leaves the record unexplained, and the standard errors (which assume
    the model is right) are then not to be trusted.

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
import time as _time
import warnings
from typing import Callable, Optional, Sequence

import numpy as np

from ..scene.types import Scene, SceneError
from .optimize import gauss_newton, optax_loop
from .params import fit_keys, implied_values, make_params
from .problem import Problem, as_result
from .quality import data_scene_mismatch, goodness


METHODS = ("gauss-newton", "lbfgs", "adam")
DATA_SCENE = ("warn", "error", "ignore")       # what identify does when the data's scene differs


@dataclasses.dataclass
class FitResult:
    """The outcome of `identify`.

    values / standard_errors: key -> float (a list of floats for a vector key).
    loss_history: the loss (SSR / n of the weighted residuals) at the start and after every
    iteration. iterations: iterations done (accepted steps for Gauss-Newton, optimiser updates
    for the optax methods). evaluations: simulations run (line search and rejected
    trial steps included). channels: the weight of every channel used. wall_time: seconds in
    all; compile_time: of which tracing and compiling; solve_time: the iterations alone.
    r2: channel -> R^2 at the returned parameters; residual_to_noise: channel -> the residual's
    RMS over the noise estimated from the record; quality: "" or "poor fit: R^2 0.12 on roll";
    data_scene: "" or how the scene stored with the data differs from the fitted one.
    implied / implied_standard_errors: key -> value of what the fitted keys imply, not fitted
    themselves: for a fitted `vessel.hull.kg` the hull's GM0 = KM - KG (`vessel.hydrostatics.gm_t`
    and `gm_l`), with the standard error of KG.
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
    r2: dict = dataclasses.field(default_factory=dict)
    residual_to_noise: dict = dataclasses.field(default_factory=dict)
    quality: str = ""
    data_scene: str = ""
    implied: dict = dataclasses.field(default_factory=dict)
    implied_standard_errors: dict = dataclasses.field(default_factory=dict)
    no_signal: dict = dataclasses.field(default_factory=dict)     # channel -> spread: left out (weight 0)

    @property
    def loss(self) -> float:
        return self.loss_history[-1] if self.loss_history else float("nan")

    @property
    def poor_fit(self) -> bool:
        return bool(self.quality)

    @property
    def status(self) -> str:
        """"converged", "NOT converged", and the quality when the fit is poor: the summary's word."""
        s = "converged" if self.converged else "NOT converged"
        return f"{s}, {self.quality}" if self.quality else s

    def to_dict(self) -> dict:
        return {"values": self.values, "standard_errors": self.standard_errors,
                "loss_history": [float(x) for x in self.loss_history], "iterations": int(self.iterations),
                "converged": bool(self.converged), "method": self.method,
                "quality": self.quality or "good", "r2": dict(self.r2),
                "residual_to_noise": dict(self.residual_to_noise), "data_scene": self.data_scene or None,
                "implied": dict(self.implied), "implied_standard_errors": dict(self.implied_standard_errors),
                "weights": dict(self.channels)}

    def to_json(self, path: Optional[str] = None, **kw) -> str:
        """The JSON text of {"values", "standard_errors", "loss_history", "iterations", "converged",
        "method", "quality" ("good" or "poor fit: R^2 0.12 on roll"), "r2", "residual_to_noise",
        "data_scene" (null, or how the data's scene differs), "implied", "implied_standard_errors",
        "weights" (channel: the weight its residual had)};
        also written to `path` when given."""
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


def identify(scene: Scene, measured, fit: Sequence[str], *, weights: Optional[dict] = None,
             method: str = "gauss-newton", max_iter: int = 50, x0: Optional[dict] = None,
             bounds: Optional[dict] = None, callback: Optional[Callable] = None,
             learning_rate: Optional[float] = None, data_scene: str = "warn") -> FitResult:
    """Fit the scene values named by `fit` (dotted keys) to `measured` (a Result or a result file).

    weights: channel -> weight ("roll", "pitch", "heave", "probes.<name>", "bodies.<name>.roll",
    ..., "connections.<name>"), default 1 / std of the
    measured channel (0 for a constant channel). method: "gauss-newton" (default), "lbfgs" or
    "adam". x0: key -> start value (default the scene's). bounds: key -> (lo, hi), None for an open
    side (default: (0, None) for positive quantities, fitted in log). callback(iteration, values,
    loss) after every iteration; returning True stops the fit. data_scene: when the measured result
    carries a scene that differs from `scene` (besides the fitted keys), "warn" (default), "error"
    (SceneError) or "ignore". Raises SceneError (naming the key) for bad input. See the module
    docstring for the details.
    """
    if method not in METHODS:
        raise SceneError("method", f"unknown method {method!r} (choose from {', '.join(METHODS)})")
    if data_scene not in DATA_SCENE:
        raise SceneError("data_scene", f"unknown choice {data_scene!r} (choose from {', '.join(DATA_SCENE)})")
    if int(max_iter) < 0:
        raise SceneError("max_iter", f"must be >= 0, got {max_iter}")
    t0 = _time.perf_counter()
    measured = as_result(measured)
    keys = fit_keys(scene, fit)
    mismatch = data_scene_mismatch(scene, measured, keys)
    if mismatch and data_scene == "error":
        raise SceneError("measured", mismatch)
    if mismatch and data_scene == "warn":
        warnings.warn(f"identify: {mismatch}; the fitted keys will absorb the difference "
                      f"(data_scene='ignore' fits without this warning)", stacklevel=2)
    params = make_params(scene, keys, x0, bounds)
    pb = Problem(scene, measured, params, weights)
    history: list = []
    t_solve = _time.perf_counter()
    if method == "gauss-newton":
        theta, it, converged, message, last = gauss_newton(pb, pb.theta0.copy(), int(max_iter), callback, history)
        final_known = True
    else:
        theta, it, converged, message, final_known = optax_loop(pb, pb.theta0.copy(), method, int(max_iter),
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
    r2, noise, quality = goodness(res, pb.data[1], pb.data[2], pb.active) if ok else ({}, {}, "")
    values = pb.values(theta)
    implied, implied_se = implied_values(scene, values, se)
    return FitResult(values=values, standard_errors=se, implied=implied, implied_standard_errors=implied_se, loss_history=[float(x) for x in history],
                     iterations=int(it), converged=bool(converged), method=method, message=message,
                     evaluations=pb.evaluations, n_residuals=pb.n, channels=dict(pb.weights), start=start,
                     wall_time=_time.perf_counter() - t0, compile_time=pb.compile_time, solve_time=solve_time,
                     correlation=corr, r2=r2, residual_to_noise=noise, quality=quality,
                     data_scene=mismatch, no_signal=dict(pb.no_signal))       # kept, whatever data_scene says: the record of the fit
