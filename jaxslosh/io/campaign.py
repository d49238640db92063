"""The campaign file (docs/reference/files.md): every case created "pending" when the campaign starts, its
statistics and spectra written as it finishes. The file is opened, written and closed for each
finished batch, so that a reader (or a --resume after a kill) always finds a consistent file."""
from __future__ import annotations

import errno
import json
import time
from typing import NamedTuple

import h5py
import numpy as np

from .._version import __version__
from .result import ResultFileError, attr_str, open_format

CAMPAIGN_FORMAT = "jaxslosh.campaign"
CASE_KEYS = ("hs", "tp", "heading", "seed", "weight")
STATS = ("std", "significant", "max", "mpm", "tz")
PENDING = "pending"
#: how long a write waits for readers: HDF5 locks the file, and a reader that holds it (a plot of
#: the campaign so far, a script polling it; in this process, a thread polling it beside
#: js.campaign: "already open for read-only") makes the writer's open fail until it closes the file
WRITE_WAIT = 120.0


def _open_for_writing(path):
    """h5py.File(path, "r+"), waiting while a reader holds HDF5's lock on it."""
    deadline = time.monotonic() + WRITE_WAIT
    while True:
        try:
            return h5py.File(path, "r+")
        except OSError as e:
            busy = isinstance(e, BlockingIOError) or e.errno in (errno.EAGAIN, errno.EWOULDBLOCK) or \
                "unable to lock file" in str(e) or "already open for read-only" in str(e)
            if not busy or time.monotonic() > deadline:
                raise
            time.sleep(0.05)


def create_campaign(path, scene_text: str, cases: dict, channels, frequency, attrs=None):
    """A new campaign file: the case table (`cases`: {hs, tp, heading, seed, weight, and the
    scatter's extra [waves] keys}), every status "pending", statistics and spectra NaN."""
    n = len(cases["hs"])
    with h5py.File(path, "w") as f:
        f.attrs["format"] = CAMPAIGN_FORMAT
        f.attrs["format_version"] = 1
        f.attrs["scene"] = scene_text
        f.attrs["jaxslosh_version"] = __version__
        for k, v in (attrs or {}).items():
            f.attrs[k] = v
        for k, v in cases.items():
            f.create_dataset(f"cases/{k}", data=np.asarray(v))
        f.create_dataset("cases/status", data=np.array([PENDING] * n, dtype=object), dtype=h5py.string_dtype())
        f.attrs["channels"] = np.array(list(channels), dtype=h5py.string_dtype())
        for ch in channels:
            for s in STATS:
                f.create_dataset(f"statistics/{ch}/{s}", data=np.full(n, np.nan))
            f.create_dataset(f"spectra/{ch}", data=np.full((n, len(frequency)), np.nan))
        f.create_dataset("spectra/frequency", data=np.asarray(frequency, dtype=float))


def write_cases(path, indices, outcomes):
    """Store finished cases: `outcomes[i]` {"status", "stats": {channel: {std, ..., spectrum}}}."""
    # each dataset written once for the batch's cases (HDF5's point selection, in increasing
    # order), not once per case: a batch's writes were one per case, channel and statistic
    done = sorted((int(i), o["stats"]) for i, o in zip(indices, outcomes) if o["stats"] is not None)
    rows = [i for i, _ in done]
    with _open_for_writing(path) as f:
        status = f["cases/status"]
        for ch in done[0][1] if done else ():
            for s in STATS:
                f[f"statistics/{ch}/{s}"][rows] = np.array([st[ch][s] for _, st in done], dtype=float)
            f[f"spectra/{ch}"][rows] = np.stack([st[ch]["spectrum"] for _, st in done])
        for i, o in zip(indices, outcomes):
            status[i] = o["status"]
        f.flush()


class Campaign(NamedTuple):
    """A campaign file read back: the case table, each case's status, {channel: {stat: (n,)}},
    the spectra's frequencies (rad/s) and {channel: (n, f)}, the scene's TOML text, the attrs."""
    cases: dict
    status: list
    statistics: dict
    frequency: np.ndarray
    spectra: dict
    scene_text: str
    attrs: dict


def load_campaign(path) -> Campaign:
    """The campaign file at `path`; one that is not one or cannot be read raises ResultFileError."""
    with open_format(path, CAMPAIGN_FORMAT, "campaign") as f:
        try:
            cases = {k: f[f"cases/{k}"][()] for k in f["cases"] if k != "status"}
            status = [attr_str(x) for x in f["cases/status"][()]]
            chans = [attr_str(c) for c in f.attrs["channels"]]
            stats = {ch: {s: f[f"statistics/{ch}/{s}"][()] for s in STATS} for ch in chans}
            freq = f["spectra/frequency"][()]
            spectra = {ch: f[f"spectra/{ch}"][()] for ch in chans}
        except KeyError as e:
            raise ResultFileError(f"{path}: a campaign dataset is missing ({e})") from None
        attrs = {k: (attr_str(v) if isinstance(v, (bytes, str)) else v) for k, v in f.attrs.items()}
    return Campaign(cases, status, stats, freq, spectra, attrs.get("scene", ""), attrs)


def write_summary(path, limits: dict, exceedance: dict, operability: float, failed: float = 0.0):
    """The limits a campaign was judged by, each one's exceedance probability, the operability and
    the share (%) of the judged weight whose cases failed (counted as not operable, as exceeding)."""
    with _open_for_writing(path) as f:
        f.attrs["limits"] = json.dumps(limits)
        f.attrs["exceedance"] = json.dumps(exceedance)
        f.attrs["operability"] = float(operability)
        f.attrs["failed_weight"] = float(failed)


def file_limits(c: Campaign) -> dict:
    try:
        return {k: float(v) for k, v in json.loads(c.attrs.get("limits", "{}") or "{}").items()}
    except (ValueError, TypeError, AttributeError):
        return {}
