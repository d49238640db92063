"""How a run ended, as a code (like diffrax's RESULTS) with its text.

The compiled loop carries the code of its first failure; the host turns it into the sentence that
the result file's `status` attribute holds (docs/reference/files.md: "ok" or a reason) and keeps the code
beside it (`status_code`). Codes are stable: files written by one version are read by the next.
"""
from __future__ import annotations

import enum
import math

import equinox as eqx
import jax
import jax.numpy as jnp


class Status(enum.IntEnum):
    OK = 0
    NEWTON = 1           # a step's Newton iterations did not converge
    NONFINITE = 2        # NaN or Inf in a step's solution
    INITIAL = 3          # the initial accelerations could not be solved
    INTERRUPTED = 4      # stopped by SIGINT or SIGTERM
    DISK_FULL = 5        # the result file could not be written further
    ERROR = 6            # another exception stopped the run
    RUNNING = 7          # the file is still being written (or its writer died without a word)

    @property
    def numerical(self) -> bool:
        return self in (Status.NEWTON, Status.NONFINITE, Status.INITIAL)


#: the short text of each code, for messages raised inside jax.jit (where no number can be formatted)
TEXT = {Status.OK: "ok", Status.NEWTON: "Newton did not converge", Status.NONFINITE: "non-finite values (NaN or Inf)",
        Status.INITIAL: "the initial accelerations could not be solved", Status.INTERRUPTED: "interrupted",
        Status.DISK_FULL: "disk full", Status.ERROR: "error", Status.RUNNING: "running"}


class RunResult(eqx.Enumeration):
    """How a run ended, as a leaf of its result (traced under `jax.jit` and batched under `vmap`,
    as optimistix's and diffrax's RESULTS): `result.outcome == RunResult.ok`. The items are in the
    order of `Status`, so an item's index is its code."""
    ok = "ok"
    newton = "jaxslosh: the run failed: Newton did not converge in a step"
    nonfinite = "jaxslosh: the run failed: non-finite values (NaN or Inf) in a step's solution"
    initial = "jaxslosh: the run failed: the initial accelerations could not be solved"
    interrupted = "jaxslosh: the run was interrupted"
    disk_full = "jaxslosh: the result file could not be written further (disk full)"
    error = "jaxslosh: another error stopped the run"
    running = "jaxslosh: the result file is still being written"


_ITEMS = (RunResult.ok, RunResult.newton, RunResult.nonfinite, RunResult.initial, RunResult.interrupted,
          RunResult.disk_full, RunResult.error, RunResult.running)
assert all(int(_ITEMS[c]._value) == int(c) for c in Status)     # an item's index is its Status code


def outcome_of(code) -> RunResult:
    """The RunResult item of a Status code (an int, or a traced or batched integer array)."""
    code = jnp.asarray(code)
    if code.ndim:           # a batch's codes: one item per run (RunResult.where takes a scalar)
        return jax.vmap(outcome_of)(code)
    out = RunResult.ok
    for c, item in enumerate(_ITEMS[1:], start=1):
        out = RunResult.where(code == c, item, out)
    return out


class Failure(eqx.Module):
    """Where a run's first numerical failure happened (leaves: traced under `jax.jit`): the step
    (0 while none, or for the initial accelerations), its scaled residual and Newton iterations."""
    step: jax.Array
    residual: jax.Array
    iterations: jax.Array


def is_traced(x) -> bool:
    """Whether a value (or a pytree of them) holds a JAX tracer: no value to check or to convert."""
    return any(isinstance(v, jax.core.Tracer) for v in jax.tree_util.tree_leaves(x))


def failure_text(code: int, step: int, h: float, err: float, iterations: int, tol: float) -> str:
    """The sentence of a numerical failure, naming the step and the time."""
    code = Status(int(code))
    if code == Status.INITIAL or step == 0:
        return f"the initial accelerations could not be solved (scaled residual {err:.3g})"
    t = step * h
    if code == Status.NONFINITE or not math.isfinite(err):
        return f"step {step} (t = {t:.6g} s): non-finite values (NaN or Inf) in the solution"
    return (f"step {step} (t = {t:.6g} s): Newton did not converge in {iterations} iterations "
            f"(scaled residual {err:.3g}, tolerance {tol:.3g})")


def code_of(status: str) -> Status:
    """The code of a status text (files written before codes were kept)."""
    if status == "ok":
        return Status.OK
    for code in (Status.NONFINITE, Status.INITIAL, Status.NEWTON, Status.INTERRUPTED, Status.DISK_FULL,
                 Status.RUNNING):
        if TEXT[code] in status:
            return code
    return Status.ERROR
