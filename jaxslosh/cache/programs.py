"""Compiled programs (and built models) kept across processes: what a second `jaxslosh run` of a
scene skips.

JAX's persistent compilation cache (set up by the CLI, cli/common.setup_jax) saves XLA's work, but
a new process still traces and lowers every program to find its cache entry: for the paper example
that is seconds, more than the XLA work the cache saves. Here a program is exported once
(`jax.export`: its StableHLO and the trees of its inputs and outputs) to a file named by everything
the trace depends on; a later process reads the file instead of tracing, and XLA's cache serves the
compilation.

What the trace depends on, hence the file's name: jaxslosh's source (every module, hashed), the JAX
version and backend, the program's name, the structure of its arguments with every static value
(the pickled tree definition: equinox's static fields, Python numbers and strings among the leaves)
and the shape and type of each array. Arrays (JAX or NumPy) are the program's inputs, as under
`eqx.filter_jit`. Where the structure does not pickle, or the folder is off or not writable, the
program is traced and compiled as usual, without a file.

Once XLA has compiled the program, its executable is added to the file (`jax.experimental.
serialize_executable`), marked with the host it was compiled for (backend, processor and its
instruction set). A later process on that host loads the executable and neither lowers the program
nor asks XLA's cache: on the mast scene, that lowering and XLA's cache lookup took about half a
second of a second process's start (docs/guide/compilation-cache.md). Another host compiles the exported
program, through XLA's cache. An executable XLA's cache gave back is not kept (see `_HITS`).

`cached` keeps a value the same way: `jaxslosh run` keeps the model it built from a scene (meshes,
element matrices, the Newton matrix's constant blocks), a second run of the scene reads it.

XLA's work on a program runs outside Python: `Program.compile_in_background` lets one program
compile while Python traces the next (`run/compiled.compile_run`).
"""
from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import pickle
import threading

import jax
import numpy as np
from jax import export
from jax.experimental import serialize_executable

from .. import staging
from . import executables
from .executables import Load, loadable, read, take, touch, write_bytes

_FOLDER: list = [None]


def use(folder: str | None):
    """Keep exported programs in `folder` (None: off, the default)."""
    _FOLDER[0] = folder


def folder() -> str | None:
    return _FOLDER[0]


@functools.cache
def _code_hash() -> bytes:
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))   # the package
    h = hashlib.sha256(f"{jax.__version__} {jax.lib.__version__}".encode())
    for dirpath, dirs, files in sorted(os.walk(root)):
        dirs.sort()
        for f in sorted(files):
            if f.endswith(".py"):
                h.update(f.encode())
                with open(os.path.join(dirpath, f), "rb") as fh:
                    h.update(fh.read())
    return h.digest()


def _is_input(x) -> bool:
    """An array (or the shape and type of one, to lower a program before its inputs exist)."""
    return isinstance(x, (jax.Array, np.ndarray, np.generic, jax.ShapeDtypeStruct))


def _aval(x):
    """Shape and type; never weakly typed: an exported program's outputs come back strongly typed,
    and a carry passed on from one program to the next must give the same name (with float64
    throughout, weak typing changes no result)."""
    return jax.ShapeDtypeStruct(tuple(x.shape), jax.dtypes.canonicalize_dtype(x.dtype))


def _key(name, treedef, leaves, options) -> str | None:
    try:
        tree = pickle.dumps(treedef)
        static = pickle.dumps([None if _is_input(x) else x for x in leaves])
    except Exception:        # a static value that does not pickle (a function made inside a call)
        return None
    h = hashlib.sha256(_code_hash())
    h.update(repr((name, jax.default_backend(), jax.config.jax_enable_x64, sorted((options or {}).items()))).encode())
    h.update(tree)
    h.update(static)
    h.update(repr([(a.shape, str(a.dtype)) for a in map(_aval, filter(_is_input, leaves))]).encode())
    return h.hexdigest()


def program_key(name: str, args: tuple, options=None) -> str | None:
    """The name of `name`'s program for arguments like `args` (what its trace depends on: see the
    module's docstring); None where a static value does not pickle."""
    leaves, treedef = jax.tree_util.tree_flatten(args)
    return _key(name, treedef, leaves, options)


def _write(path, saved: dict):
    try:
        data = pickle.dumps(saved)
    except Exception:
        return
    write_bytes(path, data)


#: JAX's persistent compilation cache hits, counted by thread: an executable XLA's cache gave back
#: serialises without its code (a process that loads it fails: "Function ... not found"), so only
#: what XLA compiled in this process is kept
_HITS = threading.local()


def _count_hit(event: str, **kwargs):
    if event == "/jax/compilation_cache/cache_hits":
        _HITS.n = _cache_hits() + 1


def _cache_hits() -> int:
    return getattr(_HITS, "n", 0)


jax.monitoring.register_event_listener(_count_hit)


class Program:
    """A program traced (or read from its file) and lowered, whose XLA compilation is still to come:
    `out` is its output tree of shapes and types (what a following program is lowered with), and
    `compile()` or `compile_in_background()` then `result()` give the callable, which takes
    arguments like the `args` it was lowered for. XLA's work runs outside Python (no GIL), so one
    program compiles in the background while Python traces the next.

    Where the file holds an executable this host compiled, there is nothing to lower or compile: it
    is loaded (also outside Python). Where it does not, the executable XLA compiles is added to the
    file (`saved`), for the next process."""

    def __init__(self, lowered, where, out_tree, loaded, options, saved=None, path=None, retrace=None, loading=None):
        self._lowered, self._where, self._out_tree, self._options = lowered, where, out_tree, options
        self._saved, self._retrace, self._loading = saved, retrace, loading
        self.path = path        # the program's file (None: not kept)
        self.loaded = loaded
        self._done: list = []
        self._thread = None
        self._ready = threading.Event()

    @property
    def out(self):
        if self._lowered is None:
            info = [jax.ShapeDtypeStruct(shape, dtype) for shape, dtype in self._saved["out"]]
        else:
            info = jax.tree_util.tree_map(lambda a: jax.ShapeDtypeStruct(a.shape, a.dtype), self._lowered.out_info)
        return info if self._out_tree is None else jax.tree_util.tree_unflatten(self._out_tree, info)

    def _compile(self):
        try:
            if self._lowered is None:
                self._done.append(self._loading.result())
                return
            hits = _cache_hits()
            compiled = self._lowered.compile(compiler_options=self._options)
            fresh = _cache_hits() == hits
            self._done.append((compiled, None))
        except BaseException as e:      # handed to the thread that asks for the result
            self._done.append((None, e))
            return
        finally:
            self._ready.set()           # the executable is kept for the next process after this
        if self.path is not None and fresh:
            try:
                executable = serialize_executable.serialize(compiled)
            except Exception:           # a backend or program that cannot be serialised: the export alone
                return
            _write(self.path, {"export": self._saved["export"], "out_tree": self._saved["out_tree"], "host": executables.host(),
                                "executable": executable,
                                "out": [(a.shape, str(a.dtype)) for a in jax.tree_util.tree_leaves(self.out)]})

    def compile_in_background(self) -> "Program":
        # a daemon thread: an interrupted run exits without waiting for XLA to finish; a run that
        # ends waits for it to keep the executable (executables.settle)
        self._thread = threading.Thread(target=self._compile, name="xla-compile", daemon=True)
        self._thread.start()
        executables.pending(self._thread)
        return self

    def result(self):
        if self._thread is not None:
            self._ready.wait()
        elif not self._done:
            self._compile()
        compiled, error = self._done[-1]
        if error is not None and self._retrace is not None:     # an executable that did not load
            return self._retrace().result()
        if error is not None:
            raise error
        where, out_tree = self._where, self._out_tree
        if out_tree is None:
            return lambda *a: compiled(*_inputs(a, where))
        return lambda *a: jax.tree_util.tree_unflatten(out_tree, compiled(*_inputs(a, where)))

    compile = result


def lower_program(name: str, fn, args: tuple, compiler_options=None, executable: bool = True) -> Program:
    """`fn(*args)` traced and lowered for arguments of this structure, shapes and static values (from
    the folder's exported program where a process traced it before, or its executable where one was
    compiled on this host), not yet compiled. Arrays among `args` may be jax.ShapeDtypeStruct: only
    their shapes and types are read."""
    leaves, treedef = jax.tree_util.tree_flatten(args)
    where = [i for i, x in enumerate(leaves) if _is_input(x)]
    avals = [_aval(leaves[i]) for i in where]
    base = folder()
    key = _key(name, treedef, leaves, compiler_options) if base else None
    if key is None:
        lowered = jax.jit(lambda *xs: fn(*_fill(treedef, leaves, where, xs))).lower(*avals)
        return Program(lowered, where, None, False, compiler_options)
    path = os.path.join(base, f"{name.replace(' ', '_')}-{key[:32]}.jaxexport")
    loading = take(path) if executable else None
    saved = loading.saved if loading is not None else read(path)
    out_tree = None
    if saved is not None:
        try:
            out_tree = pickle.loads(saved["out_tree"])
        except Exception:        # written by another version: traced again
            saved = None
    if executable and loadable(saved):
        return Program(None, where, out_tree, True, compiler_options, saved, path,
                       retrace=lambda: lower_program(name, fn, args, compiler_options, executable=False),
                       loading=loading or Load(saved))
    exported = None
    if saved is not None:
        try:
            exported = export.deserialize(saved["export"])
        except Exception:        # written by another version: traced again
            pass
    loaded = exported is not None
    if not loaded:
        trees = []

        def flat(*xs):
            out, tree = jax.tree_util.tree_flatten(fn(*_fill(treedef, leaves, where, xs)))
            trees.append(tree)
            return out
        exported = export.export(jax.jit(flat))(*avals)
        out_tree = trees[0]
        try:
            saved = {"export": exported.serialize(), "out_tree": pickle.dumps(out_tree)}
        except Exception:        # an output tree that does not pickle: no file
            return Program(jax.jit(exported.call).lower(*avals), where, out_tree, False, compiler_options)
        _write(path, saved)

    # The program's name carries its file's: JAX's persistent cache then serves it to this file's
    # program alone. An executable that cache gives back cannot be kept (see _HITS); named by the
    # file, the cache misses where the file has no executable for a program it never compiled
    # (jaxslosh's source changed, hence every file's name, and the programs did not), and XLA's
    # compile gives one to keep.
    def call(*xs):
        return exported.call(*xs)
    call.__name__ = call.__qualname__ = f"{name}_{key[:16]}".replace("-", "_").replace(" ", "_")
    return Program(jax.jit(call).lower(*avals), where, out_tree, loaded, compiler_options, saved, path)


def compile_program(name: str, fn, args: tuple, compiler_options=None):
    """`fn(*args)` compiled for arguments of this structure, shapes and static values; returns the
    compiled callable (it takes arguments like `args`) and whether it came from the folder."""
    p = lower_program(name, fn, args, compiler_options)
    return p.compile(), p.loaded


#: a value larger than this, pickled, is not kept (a large mesh's model: its file would cost more to
#: write and read than the build it saves; the paper's elastic tank, whose dense liquid blocks make
#: 75 MB, reads back in a fraction of its build)
MAX_VALUE_BYTES = 256 << 20


def cached(name: str, key, compute):
    """`compute()`, kept in the folder under a name made of `key` (pickled: the scene, say), jaxslosh's
    source, the JAX version and backend, and x64: a later process reads it instead of computing it
    again. What does not pickle (key or value), is larger than MAX_VALUE_BYTES, or finds no folder is
    computed as usual and not kept."""
    base = folder()
    try:
        blob = pickle.dumps(key) if base else None
    except Exception:
        blob = None
    if blob is None:
        return compute()
    h = hashlib.sha256(_code_hash())
    h.update(repr((name, jax.default_backend(), jax.config.jax_enable_x64)).encode())
    h.update(blob)
    path = os.path.join(base, f"{name.replace(' ', '_')}-{h.hexdigest()[:32]}.pickle")
    try:
        with open(path, "rb") as f:
            value = pickle.load(f)
        touch(path)
        return value
    except Exception:        # absent, written by another version, cut short: computed again
        pass
    value = compute()
    try:
        data = pickle.dumps(value)
    except Exception:
        return value
    if len(data) <= MAX_VALUE_BYTES:
        write_bytes(path, data)
    return value


def trim(base: str, max_bytes: int) -> int:
    """Keep the files under `base` (the exported programs, kept models, XLA's cache entries) within
    `max_bytes`: where they exceed it, the least recently used (written or read) are removed until
    three quarters of it remain. Returns the bytes removed. Whatever cannot be listed or removed (a
    file another process removed meanwhile) is left alone: a cache file removed is only work to
    redo."""
    files = []
    for dirpath, _, names in os.walk(base):
        for n in names:
            try:
                st = os.stat(os.path.join(dirpath, n))
            except OSError:
                continue
            files.append((st.st_mtime, st.st_size, os.path.join(dirpath, n)))
    total = sum(size for _, size, _ in files)
    if total <= max_bytes:
        return 0
    removed = 0
    for _, size, path in sorted(files):
        if total - removed <= 0.75 * max_bytes:
            break
        try:
            os.remove(path)
            removed += size
        except OSError:
            pass
    return removed


def _fill(treedef, leaves, where, xs):
    leaves = list(leaves)
    for i, x in zip(where, xs):
        leaves[i] = x
    return jax.tree_util.tree_unflatten(treedef, leaves)


def _inputs(args, where):
    leaves = jax.tree_util.tree_leaves(args)
    return [leaves[i] for i in where]


def no_eager_folding():
    """A context in which a jit trace stages its operations on constants even inside
    `jax.ensure_compile_time_eval()` (JAX's eager_constant_folding state; a JAX without it: nothing)."""
    state = getattr(getattr(jax, "_src", None) and jax._src.config, "eager_constant_folding", None)
    return state(False) if state is not None else contextlib.nullcontext()


def install():
    """Install the cache's hooks in jaxslosh/staging.py: called by the entry points (the command
    line's `setup_jax`, the package's public functions on first use, the campaign workers), never on
    import, so that nothing below the cache depends on whether it is imported."""
    staging.install(lower=lower_program, no_folding=no_eager_folding, key=program_key, cached=cached,
                    remember=executables.remember, folder=folder)
