"""Writing files safely: one writer per output file (an exclusive lock taken before anything is
truncated), and the checks an output path gets before any computing starts.

The lock is `fcntl.flock` on a hidden file beside the output (`.NAME.lock`): HDF5 locks the file
itself, and taking the lock on the output would truncate it first. The operating system releases
the lock when its process ends however it ends, so a killed run never leaves the output locked.
"""
from __future__ import annotations

import errno
import fcntl
import os
import resource
import shutil

import h5py


class OutputError(OSError):
    """An output file that cannot be written (busy, a directory, an input of the run, read-only, a
    file that is not ours): the command line turns it into one line and exit status 2."""


#: errors of a full disk or a file-size limit: the run ends with status "disk full"
DISK_FULL = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


#: what a chunk's write is given on top of twice its arrays: HDF5 allocates whole dataset chunks
#: (io/result.py sizes them to at most 1 MB) and its metadata
WRITE_MARGIN = 2 << 20


def is_disk_full(e: BaseException) -> bool:
    """Whether an exception (h5py wraps the operating system's) means the disk or the file size
    limit is exhausted."""
    while e is not None:
        if isinstance(e, OSError) and e.errno in DISK_FULL:
            return True
        text = str(e).lower()
        if any(s in text for s in ("no space left", "file too large", "quota exceeded")) or \
                any(f"errno = {n}" in text for n in DISK_FULL):
            return True
        e = e.__cause__ or e.__context__
    return False


def room(path: str) -> float:
    """Bytes that `path` may still grow by: the free space of its disk, and the process's file size
    limit (ulimit -f) less its current size."""
    size = os.path.getsize(path) if os.path.exists(path) else 0
    free = float(shutil.disk_usage(os.path.dirname(os.path.abspath(path))).free)
    soft, _ = resource.getrlimit(resource.RLIMIT_FSIZE)
    if soft != resource.RLIM_INFINITY:
        free = min(free, float(soft - size))
    return free


def ensure_room(path: str, nbytes: float):
    """Raise OSError(ENOSPC) before a write of about `nbytes` that would not fit: a write that fails
    half-way leaves HDF5's file in a state that cannot even be closed."""
    left = room(path)
    if 2 * nbytes + WRITE_MARGIN > left:
        raise OSError(errno.ENOSPC, f"no space left for {path}: {nbytes / 1e6:.3g} MB to write, "
                                    f"{max(left, 0) / 1e6:.3g} MB left")


class OutputLock:
    """An exclusive lock on the output `path` for one writer."""

    def __init__(self, path: str):
        self.path = os.path.abspath(path)
        folder, name = os.path.split(self.path)
        self.lock_path = os.path.join(folder, f".{name}.lock")
        self.fd = os.open(self.lock_path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(self.fd)
            self.fd = None
            raise OutputError(errno.EBUSY, f"{path}: another run is writing this file") from None
        os.ftruncate(self.fd, 0)
        os.write(self.fd, str(os.getpid()).encode())

    def release(self):
        if self.fd is None:
            return
        try:
            os.unlink(self.lock_path)
        except OSError:
            pass
        fcntl.flock(self.fd, fcntl.LOCK_UN)
        os.close(self.fd)
        self.fd = None


def jaxslosh_format(path: str):
    """The `format` attribute of an existing HDF5 file (None when it is not HDF5 or has none)."""
    try:
        with h5py.File(path, "r") as f:
            v = f.attrs.get("format")
    except (OSError, ValueError):
        return None
    return v.decode() if isinstance(v, bytes) else (None if v is None else str(v))


def check_output(path: str, inputs=(), overwrite_formats=("jaxslosh.result", "jaxslosh.sweep", "jaxslosh.campaign")) -> str | None:
    """Raise OutputError when `path` cannot take the output: a directory, a missing or read-only
    folder, one of the run's input files (the scene, the data), or an existing file that is not
    one of ours (anything else would be destroyed). Returns the format of an existing file of ours
    that will be replaced (None for a new file)."""
    if os.path.isdir(path):
        raise OutputError(errno.EISDIR, f"{path}: is a directory; give a file name")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise OutputError(errno.ENOENT, f"{path}: the folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise OutputError(errno.EACCES, f"{path}: the folder {folder} is not writable")
    OutputLock(path).release()          # busy: another run is writing it (OutputError)
    if not os.path.exists(path):
        return None
    for inp in inputs:
        if inp and os.path.exists(inp) and os.path.samefile(path, inp):
            raise OutputError(errno.EEXIST, f"{path}: is an input of this run; write the output elsewhere")
    if not os.access(path, os.W_OK):
        raise OutputError(errno.EACCES, f"{path}: exists and is not writable")
    fmt = jaxslosh_format(path)
    if fmt not in overwrite_formats:
        raise OutputError(errno.EEXIST, f"{path}: exists and is not a jaxslosh output file "
                                        f"({', '.join(overwrite_formats)}); remove it or write elsewhere")
    return fmt
