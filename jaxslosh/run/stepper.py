"""Stepping a scene by hand (`init` / `step`, as diffrax's solvers have), for users who drive the
vessel step by step: change a parameter between steps, couple another model, stop on an event.

    import jaxslosh as js
    stepper = js.Stepper(scene)             # the static model and solver, built once
    state = stepper.init()                  # t = 0: consistent accelerations, hydrostatic start
    for _ in range(100):
        state = stepper.step(state)         # one implicit step, compiled once
    frame = stepper.observe(state)          # time, position, attitude, probes, energies

`simulate` runs the same `init` and `step` (run/loop.py) inside one compiled `lax.scan`.
"""
from __future__ import annotations

from typing import Optional

import equinox as eqx
import jax

from ..assemble.system import Built
from ..io.status import Status
from ..physics.kinematics import rpy_from_quat
from ..scene.keys import with_overrides
from ..scene.types import Scene
from ..solve.linear import Solver
from .loop import Carry, Frame, core, init, loop_step, observe
from .simulate import failure_message, prepare


@eqx.filter_jit
def _init(b, solver):
    return init(b, solver)[0]


@eqx.filter_jit
def _step(b, solver, carry):
    return loop_step(b, solver, carry)[0]


@eqx.filter_jit
def _advance(b, solver, carry, n):
    return jax.lax.scan(lambda c, _: (loop_step(b, solver, c)[0], None), carry, None, length=n)[0]


@eqx.filter_jit
def _observe(b, carry):
    return observe(b, carry)


class Stepper(eqx.Module):
    """A scene's static model and solver, stepped by hand. `params` (dotted keys, traceable values)
    and `dt` as for `simulate`; each method is compiled once per model structure."""
    built: Built
    solver: Solver
    probe_names: tuple = eqx.field(static=True)

    def __init__(self, scene: Scene, params: Optional[dict] = None, *, dt: Optional[float] = None):
        setup = prepare(with_overrides(scene, dt=dt), params)
        self.built = core(setup.built)
        self.solver = setup.solver
        self.probe_names = tuple(setup.built.probes.names)

    def init(self) -> Carry:
        """The state at t = 0."""
        return _init(self.built, self.solver)

    def step(self, state: Carry) -> Carry:
        """One step. A step that fails leaves the state where it was and sets `state.code`
        (io.status.Status); `status(state)` says why."""
        return _step(self.built, self.solver, state)

    def advance(self, state: Carry, n: int) -> Carry:
        """n steps in one compiled scan (compiled once per n): what `simulate` runs between frames,
        without keeping any (benchmarks time the step with it)."""
        return _advance(self.built, self.solver, state, int(n))

    @property
    def unknowns(self) -> int:
        """The count of the step's unknowns (the rigid ones, the liquid's and the structures')."""
        return int(self.built.system.layout().n)

    def observe(self, state: Carry) -> Frame:
        """What a result frame keeps of the state: t, X0, q, omega, probes (P, 3), energies, ..."""
        return _observe(self.built, state)

    def roll_pitch_yaw(self, state: Carry):
        return rpy_from_quat(state.s.c.q)

    def probe(self, state: Carry, name: str):
        """The inertial position of a probe's material point. An unknown name: ValueError naming the
        scene's probes."""
        if name not in self.probe_names:
            raise ValueError(f"no probe named {name!r}; the scene's probes: "
                             f"{', '.join(self.probe_names) if self.probe_names else 'none'}")
        return self.observe(state).probes[self.probe_names.index(name)]

    def status(self, state: Carry) -> str:
        """"ok", or the failure that froze the state (its step, time and residual)."""
        if int(state.code) == int(Status.OK):
            return "ok"
        return failure_message(state, float(self.solver.h), self.solver.tol)

    def time(self, state: Carry):
        return state.s.t

