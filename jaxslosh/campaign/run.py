"""The client side of a campaign (`js.campaign`, `jaxslosh campaign`): the cases, their batches on
Dask (a LocalCluster of worker processes, or a given Client; one worker: in this process), the campaign file written by this
process alone as batches finish, --resume, and the scatter's exceedance and operability.

A worker that dies takes its running batch with it; Dask's scheduler then runs that batch on
another worker (its `distributed.scheduler.allowed-failures` bounds how often)."""
from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading
import time
import warnings
from typing import NamedTuple, Optional

import jax
import numpy as np

from ..assemble.hull import hull_waves
from ..cache import programs
from ..io.campaign import PENDING, create_campaign, load_campaign, write_cases, write_summary
from ..io.output import OutputLock
from ..run.guard import Interrupted, interrupts
from ..run.progress import Progress, wanted
from ..scene.load import load_scene
from ..scene.campaign import channels, not_radians
from ..scene.types import CampaignTable, Scene, SceneError
from .cases import Cases, Scatter, case_scene, case_values, make_cases, read_scatter
from .stats import STATISTICS, frequencies, operability
from .worker import run_batch

#: cases per vmapped batch: enough to fill a core's vector units, few enough to share cases out
BATCH = 8


class CampaignError(ValueError):
    """Input a campaign cannot take (a file to resume that is another campaign, a bad limit):
    one line, exit status 2 on the command line. The message names the argument as js.campaign
    takes it (`limits=`, `seeds=`, `resume=`, `duration=`); `cli` as the command line does
    (`--limits`, ...), which `jaxslosh campaign` prints."""

    def __init__(self, message: str, cli: Optional[str] = None):
        super().__init__(message)
        self.cli = cli if cli is not None else message


class CampaignResult(NamedTuple):
    cases: Cases
    status: list                 # per case "ok" | "pending" | a reason
    statistics: dict             # {channel: {stat: (n,)}}
    frequency: np.ndarray        # (f,) rad/s
    spectra: dict                # {channel: (n, f)}
    run_now: int
    done_before: int
    failed: int
    wall: float
    limits: dict                 # {channel: limit}
    exceedance: dict             # {channel: scatter-weighted probability of exceeding its limit}
    operability: float           # % of the scatter's weight whose cases stay within every limit
    failed_weight: float = float("nan")   # % of the judged weight whose cases failed (not operable)
    # wall seconds of the campaign's phases: "setup" (the cases' scenes checked), "start" (the
    # workers' cluster started; 0 in this process), "first" (until the first batch came back: a
    # worker's model, program and first batch), "cases" (the rest of the batches), "write" (the
    # campaign file, within the last two), "other"
    phases: dict = {}


class CampaignInterrupted(Interrupted):
    """A campaign stopped by SIGINT or SIGTERM after a finished batch: the cases done so far are in
    its file (`output`), and `--resume` (resume=True) runs the others. `report`: one line saying so."""

    def __init__(self, how: str, done: int, total: int, run_now: int, output: Optional[str]):
        super().__init__(how)
        self.done, self.total, self.run_now, self.output = done, total, run_now, output
        kept = (f", kept in {output}; the same command with --resume runs the other {total - done}"
                if output else "")
        self.report = f"interrupted ({how}): {done} of {total} cases done ({run_now} in this run){kept}"


def channel_names(scene: Scene) -> list:
    return channels(scene.probes, scene.mooring, scene.bodies, scene.connections)


class Settings(NamedTuple):
    """A campaign's headings (rad; None: the template's), seeds, duration (None: the scene's) and
    limits: the arguments given, else the scene's `[campaign]` table, else the defaults."""
    headings: list | None
    seeds: int
    duration: float | None
    limits: dict


def settings(template: Scene, headings=None, seeds=None, duration=None, limits=None) -> Settings:
    """What a campaign of `template` runs with: each argument that is not None wins over the scene's
    `[campaign]` table (limits as a whole: given limits replace the scene's, {} means none)."""
    table = template.campaign or CampaignTable()
    if headings is None and table.headings is not None:
        headings = list(table.headings)
    return Settings(None if headings is None else [float(h) for h in np.atleast_1d(headings)],
                    int(seeds if seeds is not None else table.seeds if table.seeds is not None else 1),
                    duration if duration is not None else table.duration,
                    dict(limits) if limits is not None else table.limit_map)


def _frequency_grid(scene: Scene) -> np.ndarray:
    sim = scene.simulation
    n_steps = int(round(sim.duration / sim.dt))
    every = max(1, int(sim.save_every))
    dt_frame = sim.dt * every
    t = np.arange(n_steps // every + 1) * dt_frame
    kept = int(np.count_nonzero(t >= scene.waves.ramp - 1e-9 * max(1.0, scene.waves.ramp)))
    if kept < 16:
        why = f"the campaign's records keep {kept} frames after waves.ramp = {scene.waves.ramp:g} s: give a longer "
        raise CampaignError(why + "duration", cli=why + "--duration")
    return frequencies(kept, dt_frame)


def _case_table(cases: Cases) -> dict:
    d = {"hs": cases.hs, "tp": cases.tp, "heading": cases.heading, "seed": cases.seed, "weight": cases.weight}
    d.update(cases.extra)
    return d


def _check_limits(limits, chans) -> dict:
    out = {}
    for k, v in (limits or {}).items():
        if k not in chans:
            why = f"not a channel of this scene ({', '.join(chans)})"
            raise CampaignError(f"limits[{k!r}]: {why}", cli=f"--limits {k}: {why}")
        if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
            raise CampaignError(f"limits[{k!r}]: must be a positive number, got {v!r}",
                                cli=f"--limits {k}: must be a positive number, got {v!r}")
        out[k] = float(v)
    return out


def campaign(scene, scatter, headings=None, seeds: int | None = None, duration: Optional[float] = None,
             client=None, *,
             output: Optional[str] = None, limits: Optional[dict] = None, resume: bool = False,
             workers: int = 2, batch: int = BATCH, progress: Optional[bool] = None,
             cache_dir: Optional[str] = None) -> CampaignResult:
    """Run the scene (its `[waves]` table the template) for every scatter cell x heading x seed on
    Dask. `scatter`: a CSV path or text (read_scatter) or a Scatter; `headings` (rad, default the
    template's); `seeds` per cell and heading (the template's `waves.seed` + 0 .. seeds - 1);
    `duration` replaces the scene's; `limits` {channel: limit} (rad for roll and pitch, m). Left out
    (None), `headings`, `seeds`, `duration` and `limits` are the scene's `[campaign]` table's where
    it gives them (given limits replace the table's as a whole; {}: none). `client`: a
    dask.distributed Client, else a LocalCluster of `workers` processes is started and closed here
    (`workers=1`: the batches run in this process, one after the other, with no cluster).
    `output`: the campaign file (written as batches finish, locked against a second writer);
    `resume`: keep its "ok" cases. `cache_dir`:
    the workers' persistent compilation cache (default: this process's, jax_compilation_cache_dir)."""
    t_start = time.perf_counter()
    phases = {}
    template = load_scene(scene) if isinstance(scene, (str, os.PathLike)) else scene
    if template.waves is None or not template.waves.irregular:
        raise SceneError("waves.type", "a campaign's template is an irregular sea: type = \"jonswap\" or "
                                       "\"pierson-moskowitz\"")
    if not template.text:
        raise CampaignError("the scene has no TOML text (a campaign's cases are written as scene files): "
                            "load it with js.load_scene")
    sc = scatter if isinstance(scatter, Scatter) else read_scatter(scatter)
    headings, seeds, duration, limits = settings(template, headings, seeds, duration, limits)
    heads = [template.waves.heading] if headings is None else headings
    bad = not_radians(headings or [])
    if bad:
        raise CampaignError(f"headings: {bad}")
    if seeds < 1:
        raise CampaignError(f"seeds: must be at least 1, got {seeds}", cli=f"--seeds: must be at least 1, got {seeds}")
    cases = make_cases(sc, heads, seeds, template.waves.seed)
    scenes = []
    for i in range(cases.n):               # every case checked as its scene file would be, before running
        v = case_values(cases, i)
        try:
            scenes.append(case_scene(template, v, duration))
        except SceneError as e:
            shown = ", ".join(f"{k} = {x:g}" for k, x in v.items())
            raise SceneError(e.key, f"{str(e)[len(e.key) + 2:] if e.key else e} (case {i}: {shown})") from None
    chans = channel_names(template)
    lim = _check_limits(limits, chans)
    freq = _frequency_grid(scenes[0])
    n = cases.n
    status = [PENDING] * n
    stats = {ch: {s: np.full(n, np.nan) for s in STATISTICS} for ch in chans}
    spectra = {ch: np.full((n, freq.size), np.nan) for ch in chans}
    lock = OutputLock(output) if output else None
    phases["setup"] = time.perf_counter() - t_start
    attrs = {"record_duration": float(scenes[0].simulation.duration - scenes[0].waves.ramp), "seeds": int(seeds),
             "headings": np.asarray(heads, dtype=float)}
    try:
        done_before = 0
        if output and resume and os.path.exists(output):
            old = load_campaign(output)
            _check_resume(old, template, cases, chans, attrs, output)
            status = list(old.status)
            stats = {ch: {s: np.array(old.statistics[ch][s]) for s in STATISTICS} for ch in chans}
            spectra = {ch: np.array(old.spectra[ch]) for ch in chans}
            done_before = sum(s == "ok" for s in status)
        elif output:
            create_campaign(output, template.text, _case_table(cases), chans, freq, attrs)
        todo = [i for i in range(n) if status[i] != "ok"]
        counts = [0, 0]
        cache_dir = cache_dir or jax.config.jax_compilation_cache_dir or None
        try:
            _run(template, duration, cases, scenes, todo, client, workers, batch, output, status, stats, spectra,
                 progress, (cache_dir, _programs_dir(cache_dir)), counts, phases)
        except Interrupted as e:
            raise CampaignInterrupted(str(e), sum(x == "ok" for x in status), n, counts[0], output) from None
        run_now, failed = counts
    finally:
        if lock is not None:
            lock.release()
    ok = np.array([s == "ok" for s in status])
    bad = np.array([s not in ("ok", PENDING) for s in status])
    ops = operability(stats, cases.weight, ok, lim, float(scenes[0].simulation.duration - scenes[0].waves.ramp),
                      failed=bad)
    if output and lim:
        write_summary(output, lim, ops["exceedance"], ops["operability"], ops["failed"])
    wall = time.perf_counter() - t_start
    phases["other"] = wall - sum(v for k, v in phases.items() if k != "write")    # writing is within the batches
    return CampaignResult(cases, status, stats, freq, spectra, run_now, done_before, failed,
                          wall, lim, ops["exceedance"], ops["operability"], ops["failed"], phases)


def _resume_error(path, why):
    return CampaignError(f"resume: {path} {why}", cli=f"--resume: {path} {why}")


def _check_resume(old, template, cases, chans, attrs, path):
    if old.scene_text != template.text:
        raise _resume_error(path, "holds a campaign of another scene (its scene text differs)")
    same = all(k in old.cases and np.array_equal(np.asarray(old.cases[k], dtype=float), np.asarray(v, dtype=float))
               for k, v in _case_table(cases).items())
    if not same or len(old.status) != cases.n:
        raise _resume_error(path, "holds other cases (scatter, headings or seeds differ)")
    if list(old.statistics) != chans or abs(float(old.attrs.get("record_duration", -1)) - attrs["record_duration"]) > 1e-12:
        raise _resume_error(path, "was run with another duration or other channels")


def _structure(scene: Scene) -> tuple:
    w = scene.waves
    # the wetted hull's wave pressure is compiled for its depth and frequency range (campaign/worker.structure_scene)
    return (w.components, w.directions if w.spreading > 0 else 1) + ((w.depth, w.omega_range) if hull_waves(scene)
                                                                     else ())


def _batches(scenes, todo, batch):
    """Pending cases in batches of `batch`, each of one sea structure, in case order."""
    groups: dict = {}
    for i in todo:
        groups.setdefault(_structure(scenes[i]), []).append(i)
    return [idx[k:k + batch] for idx in groups.values() for k in range(0, len(idx), batch)]


@contextlib.contextmanager
def _sigint_ignored():
    """SIGINT ignored while the local cluster starts its worker processes, which inherit that: a
    Ctrl-C at the terminal reaches the whole process group, and workers that took it would die
    with tracebacks while this process closes them in order (their batches are cancelled here)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _quiet_cancellations():
    """On a worker: a batch cancelled by an interrupted campaign is expected, not a warning."""
    logging.getLogger("distributed.worker.state_machine").setLevel(logging.ERROR)


def _quiet_closing():
    """On a worker or its nanny, as our own cluster closes: the heartbeats that race with the
    scheduler's shutdown ("Failed to communicate with scheduler during heartbeat") lose nothing."""
    for n in ["distributed"] + [n for n in logging.root.manager.loggerDict if n.startswith("distributed.")]:
        logging.getLogger(n).setLevel(logging.CRITICAL + 1)


@contextlib.contextmanager
def _quiet_dask():
    """Dask's loggers in this process silenced while a campaign closes its cluster: after an
    interruption, the lost and cancelled batches it reports are the ones the interruption stopped."""
    names = ["distributed"] + [n for n in logging.root.manager.loggerDict if n.startswith("distributed.")]
    levels = {n: logging.getLogger(n).level for n in names}
    for n in names:
        logging.getLogger(n).setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for n, lv in levels.items():
            logging.getLogger(n).setLevel(lv)


def _programs_dir(cache_dir):
    """The workers' exported programs' folder (cache/programs.py): this process's (the command
    line's, beside its compilation cache), else one beside the given compilation cache."""
    return programs.folder() or (os.path.join(cache_dir, "jaxslosh-programs") if cache_dir else None)


def _in_process(template, duration, cases, scenes, batches, batch, caches):
    """One worker and no client: the batches in this process, one after the other. A LocalCluster
    of one worker process cost its start (the processes, their imports, the model and the program
    read back) and a copy of every result, for the same single core's work (docs/benchmarks.md)."""
    # the folders a worker is given are set in this process for the campaign alone (js.campaign's
    # caller keeps its own settings)
    kept = (programs.folder(), jax.config.jax_compilation_cache_dir,
            jax.config.jax_persistent_cache_min_compile_time_secs, jax.config.jax_persistent_cache_min_entry_size_bytes)
    try:
        for idx in batches:
            try:
                outcomes = run_batch(template.text, template.path, duration, [case_values(cases, i) for i in idx],
                                     batch, *caches, scenes=[scenes[i] for i in idx])
            except Exception as e:          # a batch that raised: its cases fail with the reason, as on Dask
                outcomes = _raised(e, idx)
            yield idx, outcomes
    finally:
        programs.use(kept[0])
        jax.config.update("jax_compilation_cache_dir", kept[1])
        # the worker's thresholds too (campaign/worker.py configure_jax): with them left at zero, the
        # caller's later compiles all went to (and came back from) XLA's cache
        jax.config.update("jax_persistent_cache_min_compile_time_secs", kept[2])
        jax.config.update("jax_persistent_cache_min_entry_size_bytes", kept[3])


def _raised(e, idx):
    reason = "error: " + " ".join(f"{type(e).__name__}: {e}".split())[:300]
    return [{"status": reason, "stats": None} for _ in idx]


def _on_dask(client, template, duration, cases, batches, batch, caches, futures):
    from dask.distributed import as_completed      # Dask imported only where a cluster is used (a second of start)
    for idx in batches:
        values = [case_values(cases, i) for i in idx]
        fut = client.submit(run_batch, template.text, template.path, duration, values, batch, *caches,
                            pure=False, retries=1)
        futures[fut] = idx
    for fut in as_completed(list(futures)):
        idx = futures[fut]
        try:
            outcomes = fut.result()
        except Exception as e:          # a batch that raised: its cases fail with the reason
            outcomes = _raised(e, idx)
        yield idx, outcomes


def _run(template, duration, cases, scenes, todo, client, workers, batch, output, status, stats, spectra, progress,
         caches, counts, phases):
    """Run the cases `todo`, storing each batch's outcomes as it finishes; counts[:] = [cases run,
    cases failed] as they go (read after an interruption too); `phases` gets the wall seconds of
    the start, the first batch, the others and the writing (CampaignResult.phases)."""
    if not todo:
        return
    t0 = time.perf_counter()
    own = client is None
    local = own and int(workers) == 1
    cluster = None
    if own and not local:
        from dask.distributed import Client, LocalCluster
        with warnings.catch_warnings(), _sigint_ignored():   # the dashboard moves off a taken 8787: say nothing
            warnings.filterwarnings("ignore", message=".*already in use.*")
            cluster = LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True,
                                   dashboard_address=None)
        client = Client(cluster)
        client.run(_quiet_cancellations)
    phases["start"] = time.perf_counter() - t0 if cluster is not None else 0.0
    bar = Progress(enabled=wanted() if progress is None else progress)
    bar.phase("cases", "cases", total=len(todo), unit="case")
    run_now = failed = 0
    # SIGINT / SIGTERM: asked, then looked at after each finished batch (run/guard.py): a
    # KeyboardInterrupt raised where the signal lands, inside Dask's callbacks, can be swallowed
    # there, and the campaign went on to its end
    guard = interrupts()
    stop = guard.__enter__()
    futures: dict = {}
    stopped = False
    batches = _batches(scenes, todo, batch)
    t_cases, writing = time.perf_counter(), 0.0
    try:
        done = (_in_process(template, duration, cases, scenes, batches, batch, caches) if local else
                _on_dask(client, template, duration, cases, batches, batch, caches, futures))
        for idx, outcomes in done:
            if "first" not in phases:
                phases["first"] = time.perf_counter() - t_cases
            for i, o in zip(idx, outcomes):
                status[i] = o["status"]
                if o["stats"] is not None:
                    for ch, st in o["stats"].items():
                        for s in STATISTICS:
                            stats[ch][s][i] = st[s]
                        spectra[ch][i] = st["spectrum"]
                failed += o["status"] != "ok"
            if output:
                tw = time.perf_counter()
                write_cases(output, idx, outcomes)
                writing += time.perf_counter() - tw
            run_now += len(idx)
            counts[:] = [run_now, failed]
            bar.update(run_now)
            stop.check()
    except KeyboardInterrupt:
        stopped = True
        raise
    finally:
        phases["cases"] = time.perf_counter() - t_cases - phases.get("first", 0.0)
        phases["write"] = writing
        guard.__exit__(None, None, None)
        bar.close()
        # our own cluster closes quietly: its nanny kills a worker that XLA's threads keep alive past
        # its grace time ("still alive after 4.0 seconds, killing"), which loses nothing here
        with _quiet_dask() if stopped or cluster is not None else contextlib.nullcontext():
            if stopped and futures:
                with contextlib.suppress(Exception):
                    client.cancel(list(futures))
            if cluster is not None:
                with contextlib.suppress(Exception):
                    client.run(_quiet_closing)
                    client.run(_quiet_closing, nanny=True)
                client.close()
                cluster.close()
