"""Executables kept in the programs' folder (cache/programs.py), and their loading ahead of use.

A program's file (cache/programs.py) keeps, beside the exported program, the executable XLA compiled for
this host. Loading it is XLA's work, outside Python's lock, and the largest part of what a second
`jaxslosh run` of a scene does before its first step (docs/guide/compilation-cache.md). So the command line
starts loading the executables its last run of the same command line used (`preload`, called by
jaxslosh/entry.py before the package's modules are imported), and the run's `lower_program` takes
them loaded or still loading (`take`).

This module imports only the standard library, and JAX only when it has an executable to load: it
runs before the rest of jaxslosh is imported, and before the command line has checked the scene
(which it does without JAX, so that a bad scene is answered at once).
"""
from __future__ import annotations

import functools
import hashlib
import os
import pickle
import tempfile
import threading


def cache_folder() -> tuple[str | None, str | None]:
    """The command line's cache folders (docs/guide/compilation-cache.md): JAX's persistent compilation cache
    in $JAXSLOSH_CACHE_DIR, else $XDG_CACHE_HOME/jaxslosh/xla (JAXSLOSH_CACHE_DIR="" turns both
    off), and the programs' folder in it; where the user set JAX_COMPILATION_CACHE_DIR, JAX's is
    theirs (None here) and the programs' folder lies beside it."""
    if os.environ.get("JAX_COMPILATION_CACHE_DIR"):
        return None, os.path.join(os.environ["JAX_COMPILATION_CACHE_DIR"], "jaxslosh-programs")
    d = os.environ.get(CACHE_ENV)
    if d is None:
        d = os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "jaxslosh", "xla")
    return (d, os.path.join(d, "programs")) if d else (None, None)


CACHE_ENV = "JAXSLOSH_CACHE_DIR"


def read(path) -> dict | None:
    """A program's file: the exported program (`export`) and its output tree (`out_tree`, pickled
    apart: its node types are jaxslosh's, which this module must not import); where a process
    compiled it, the executable (`executable`, with its outputs' shapes `out`) and the host it was
    compiled for (`host`). None where absent or unreadable."""
    try:
        with open(path, "rb") as f:
            saved = pickle.load(f)
    except Exception:        # absent, written by another version, cut short: traced again
        return None
    touch(path)
    return saved if isinstance(saved, dict) and "export" in saved and "out_tree" in saved else None


def loadable(saved: dict | None) -> bool:
    """The file holds an executable compiled for this host."""
    return saved is not None and saved.get("host") == host() and "executable" in saved


@functools.cache
def host() -> str:
    """What an executable compiled here needs of the machine that runs it: XLA compiles for this
    backend and this processor's instruction set (a cache folder shared by several machines, on a
    cluster's network drive, must not hand one machine's executable to another)."""
    cpu = ""
    try:
        with open("/proc/cpuinfo") as f:
            cpu = "".join(sorted({ln for ln in f if ln.startswith(("model name", "flags"))}))
    except OSError:
        import platform
        cpu = platform.processor() or platform.machine()
    import jax
    return hashlib.sha256(f"{jax.default_backend()} {jax.devices()[0].device_kind} {cpu}".encode()).hexdigest()


def write_bytes(path, data: bytes):
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), suffix=".tmp")
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)      # whole or absent, for a process that reads it meanwhile
    except Exception:
        pass                       # a cache that cannot be written is no cache, not an error


def touch(path):
    """A file read is a file used: programs.trim removes the least recently used first."""
    try:
        os.utime(path)
    except OSError:
        pass


class Load:
    """An executable being loaded in a thread of its own (XLA's work, outside Python's lock)."""

    def __init__(self, saved: dict):
        self.saved = saved
        self._done: list = []
        # a daemon thread: a process that ends meanwhile does not wait for it (but see `settle`)
        self._thread = threading.Thread(target=self._load, name="xla-load", daemon=True)
        self._thread.start()

    def _load(self):
        try:
            _lapack_ready()
            from jax.experimental import serialize_executable
            self._done.append((serialize_executable.deserialize_and_load(*self.saved["executable"]), None))
        except BaseException as e:      # handed to the thread that asks for the result
            self._done.append((None, e))

    def result(self):
        """(executable, None), or (None, the exception that stopped its loading)."""
        self._thread.join()
        return self._done[0]


@functools.cache
def _lapack_ready():
    """jaxlib's LAPACK kernels find LAPACK (SciPy's) when a program that calls them is first lowered;
    an executable read back is never lowered, and would call through null pointers."""
    import jax
    try:
        from jax._src.lax.linalg import initialize_lapack
        initialize_lapack()
    except Exception:       # a JAX that moved it: a lowering does it
        f64 = jax.numpy.float64
        jax.jit(jax.numpy.linalg.solve).lower(jax.ShapeDtypeStruct((2, 2), f64), jax.ShapeDtypeStruct((2,), f64))


#: executables loading ahead of their programs' lowering (`preload`), by file
_PRELOADED: dict = {}
#: threads that compile programs and keep their executables (`pending`)
_PENDING: list = []
#: the folder and the name under which this process's programs are remembered (`preload`)
_HINT: list = [None, None]


def preload(folder: str | None, hint: str | None):
    """Start loading, in the background, the executables the last process given the same `hint` (a
    command line) loaded or compiled (`remember`); a later programs.lower_program of one of them
    takes it (`take`) as it is, loaded or still loading. A wrong hint costs a load that nobody uses;
    it never gives a program another's executable: each is found by its own file's name."""
    _HINT[:] = [folder, hint]
    if not folder or hint is None:
        return
    try:
        with open(_hint_path(folder, hint)) as f:
            names = f.read().split()
    except OSError:
        return
    for name in names:
        path = os.path.join(folder, name)
        saved = read(path)
        if path not in _PRELOADED and loadable(saved):
            _PRELOADED[path] = Load(saved)


def take(path) -> Load | None:
    """The executable of the program file `path`, loading ahead since `preload`; None if it is not."""
    return _PRELOADED.pop(path, None)


def remember(paths):
    """Name the program files `paths` as those to load ahead for the next process given this one's
    hint (nothing where `preload` was not called with one)."""
    folder, hint = _HINT
    paths = [p for p in paths if p]
    if folder and hint is not None and paths:
        write_bytes(_hint_path(folder, hint), "\n".join(os.path.basename(p) for p in paths).encode())


def pending(thread: threading.Thread):
    """A thread that compiles, then keeps its executable in the folder: `settle` waits for it."""
    _PENDING[:] = [t for t in _PENDING if t.is_alive()] + [thread]


def settle():
    """Wait for the executables still loading ahead (dropping those unused) and for those being
    written: a process must not end while XLA works in one of its threads, and a run that compiled
    its programs keeps them for the next."""
    while _PRELOADED:
        _PRELOADED.popitem()[1].result()
    while _PENDING:
        _PENDING.pop().join()


def _hint_path(folder, hint):
    return os.path.join(folder, f"hint-{hashlib.sha256(hint.encode()).hexdigest()[:32]}.txt")
