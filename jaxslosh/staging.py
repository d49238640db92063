"""How jaxslosh's programs are staged for XLA, below everything that stages them: the XLA options of
the run's programs, `staged` for the build's jax.numpy steps, and the compiled kernels of the finite
elements.

The compile cache (jaxslosh/cache: programs exported and kept across processes, their executables,
the preload) sits above the modules that compile: they call `lower_program`, `compile_program`,
`program_key`, `cached`, `remember`, `folder` and `no_eager_folding` here, and the entry points
install the cache's own (cache/programs.py `install`, called by the command line's `setup_jax`,
by the package's public functions on first use, e.g. `js.simulate`, and by the campaign workers).
Without it the same calls trace and compile in the process, with the same options and results,
and keep nothing.
"""
from __future__ import annotations

import contextlib
import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from threadpoolctl import threadpool_limits

_JAXLIB = tuple(int(p) for p in jax.lib.__version__.split(".")[:2] if p.isdigit())

#: XLA options of the run's programs compiled ahead of time (run/compiled.py: `jaxslosh run`, and
#: `js.simulate` called outside any transformation; JAX takes options only for a top-level jit, so
#: js.simulate inside a user's jit keeps XLA's defaults, and agrees to round-off). XLA's classic CPU
#: loop emitters compile the step's many small fusions in 30-40 % less time than its default fusion
#: emitters, and the step runs as fast (docs/guide/compilation-cache.md). A field of XLA's shared
#: debug options: other backends accept it and leave it unused. jaxlib 0.11 removed the field (its
#: CPU backend has only the fusion emitters left) and refuses every compilation that names it.
XLA_OPTIONS = {"xla_cpu_use_fusion_emitters": False} if _JAXLIB < (0, 11) else {}
#: XLA options of a program that runs once (the run's initial state): its optimisation off, which
#: halves its XLA work, while it still runs in less time than a few steps
START_OPTIONS = {**XLA_OPTIONS, "xla_backend_optimization_level": 0}


class _Done:
    """A compilation already finished, in the shape of a background one (`result()`; no file)."""
    path = None

    def __init__(self, value):
        self.value = value

    def result(self):
        return self.value


class PlainProgram:
    """`fn(*args)` traced and lowered in this process, nothing kept: the programs of a process that
    has not imported the compile cache."""

    def __init__(self, fn, args, compiler_options=None):
        self.lowered = jax.jit(fn).lower(*args)
        self.options = compiler_options
        self.loaded = False

    def compile(self):
        return self.lowered.compile(self.options)

    def compile_in_background(self):
        return _Done(self.compile())


#: what a process without the compile cache does: trace and compile here, name and keep nothing
_PLAIN = {"lower": lambda name, fn, args, compiler_options=None: PlainProgram(fn, args, compiler_options),
          "no_folding": contextlib.nullcontext, "key": lambda name, args, options=None: None,
          "cached": lambda name, key, compute: compute(), "remember": lambda paths: None, "folder": lambda: None}
_IMPL = dict(_PLAIN)


def install(**hooks):
    """The compile cache's hooks (cache/programs.py `install`): `lower(name, fn, args,
    compiler_options)`, `no_folding()` (a context in which a jit trace stages its operations on
    constants), `key(name, args, options)`, `cached(name, key, compute)`, `remember(paths)`,
    `folder()`; `install()` with none: back to the plain ones."""
    unknown = set(hooks) - set(_PLAIN)
    if unknown:
        raise TypeError(f"unknown staging hooks {sorted(unknown)}")
    _IMPL.clear()
    _IMPL.update(_PLAIN, **hooks)


def installed() -> bool:
    """Whether a compile cache installed its hooks."""
    return _IMPL["lower"] is not _PLAIN["lower"]


def lower_program(name: str, fn, args: tuple, compiler_options=None):
    """`fn(*args)` lowered for arguments of this structure (a program with `compile()` and
    `compile_in_background()`; from the compile cache where it is imported)."""
    return _IMPL["lower"](name, fn, args, compiler_options)


def compile_program(name: str, fn, args: tuple, compiler_options=None):
    """`fn(*args)` compiled for arguments of this structure, shapes and static values; returns the
    compiled callable (it takes arguments like `args`) and whether it came from the cache's folder."""
    p = lower_program(name, fn, args, compiler_options)
    return p.compile(), p.loaded


def program_key(name: str, args: tuple, options=None):
    """A name for `name`'s program for arguments like `args` (None without the compile cache, or
    where a static value does not pickle): compiled programs of the same name are reused."""
    return _IMPL["key"](name, args, options)


def cached(name: str, key, compute):
    """`compute()`, kept by the compile cache where it keeps programs in a folder."""
    return _IMPL["cached"](name, key, compute)


def remember(paths):
    """Name program files for the next process of the same command line to load ahead."""
    return _IMPL["remember"](paths)


def folder():
    """The folder where programs are kept (None: not kept)."""
    return _IMPL["folder"]()


def no_eager_folding():
    """A context in which a jit trace stages its operations on constants even inside
    `jax.ensure_compile_time_eval()` (nothing where the compile cache is not imported)."""
    return _IMPL["no_folding"]()


def staged(fn):
    """`fn` under equinox's filter_jit, traced whole even where the build evaluates eagerly
    (run/simulate.prepare, inside `jax.ensure_compile_time_eval()`): the build's few steps written
    with jax.numpy become one compiled program each, where op by op every line compiled a tiny XLA
    program of its own (seconds in a fresh process). Inside an outer trace it is inlined."""
    jitted = eqx.filter_jit(fn)

    @functools.wraps(fn)
    def call(*args, **kwargs):
        with no_eager_folding():
            return jitted(*args, **kwargs)
    return call


def evaluated(fn, static_argnums=()):
    """`fn` (a build step written with jax.numpy) as one compiled program, where op by op every line
    compiled a tiny XLA program of its own. With concrete arguments it is evaluated now, even inside
    an outer trace (vmap, jit: its arrays stay concrete, as its eager operations left them); with
    traced ones it is staged into the caller's program. Its operations on constants are staged in
    either case (`no_eager_folding`), not evaluated one by one."""
    static = (static_argnums,) if isinstance(static_argnums, int) else tuple(static_argnums)
    jitted = jax.jit(fn, static_argnums=static)

    @functools.wraps(fn)
    def call(*args):
        with no_eager_folding():
            if any(isinstance(a, jax.core.Tracer) for a in jax.tree_util.tree_leaves(args)):
                return jitted(*args)
            program = jitted.lower(*args).compile()      # cached by JAX: compiled once per signature
        return program(*(a for i, a in enumerate(args) if i not in static))
    return call


def one_blas_thread():
    """A context in which NumPy's and SciPy's BLAS (OpenBLAS, which jaxlib's LAPACK calls use too)
    run on one thread: the build's host-side algebra (modal bases, factors of a few hundred to a few
    thousand rows, many small multi-column solves) gains nothing from a second thread, and on a busy
    machine its threads' waits for each other cost several times the work (scenes/flng_side_by_side.toml:
    the face-normal tanks' bases 5 s of CPU against 0.4 s; docs/benchmarks.md). XLA's own threads are
    not BLAS's: the run's compiled programs are unaffected."""
    return threadpool_limits(limits=1, user_api="blas")


def on_device(x):
    """`jnp.asarray(x)` without a compile: JAX lifts a NumPy array or scalar through a primitive that,
    outside a trace, compiles a tiny XLA program for every new shape and dtype; `jax.device_put`
    copies it (same dtype, same weak type; inside a trace the same constant). Anything else (JAX
    arrays, tracers, Python lists) goes to `jnp.asarray`."""
    if isinstance(x, (np.ndarray, np.generic)) and not isinstance(x, np.ma.MaskedArray):
        return jax.device_put(x)
    return jnp.asarray(x)
