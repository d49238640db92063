"""`jaxslosh campaign`: the scene's sea template over a scatter of sea states x headings x seeds on
Dask (campaign/), statistics written to a campaign file as cases finish. The options left out come
from the scene's `[campaign]` table (scene/campaign.py); the command line wins."""
from __future__ import annotations

import math
import os
import sys

from ..campaign.cases import ScatterError
from ..campaign.run import CampaignError, campaign, channel_names
from ..io.campaign import PENDING
from ..io.output import OutputError
from ..io.result import ResultFileError
from ..scene.campaign import not_radians
from .common import COMMANDS, InputError, load, positive, setup_jax, writable_output


def add_parsers(sub):
    s = sub.add_parser("campaign", help=COMMANDS["campaign"][1])
    s.add_argument("scene")
    s.add_argument("--scatter", required=True, metavar="SCATTER.csv",
                   help="CSV: hs, tp, probability or occurrences; more columns set [waves] keys (gamma, ...)")
    s.add_argument("--headings", metavar="B1,B2,...",
                   help="wave headings in rad (default: campaign.headings, else waves.heading)")
    s.add_argument("--seeds", type=int, help="random seeds per cell and heading (default: campaign.seeds, else 1)")
    s.add_argument("--duration", type=float, help="s, replaces the scene's (default: campaign.duration, else "
                                                  "simulation.duration)")
    s.add_argument("--limits", metavar="KEY=VALUE,...",
                   help="limits per channel: roll=0.1,probe.B=0.5 (replace the scene's [campaign.limits])")
    g = s.add_mutually_exclusive_group()
    g.add_argument("--workers", type=int, help="worker processes of a local Dask cluster (default 2)")
    g.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler (tcp://host:8786)")
    s.add_argument("--batch", type=int, default=8, help="cases per vmapped batch (default 8)")
    s.add_argument("--resume", action="store_true", help="keep the finished cases of the existing file")
    s.add_argument("--no-progress", action="store_true")
    s.add_argument("-o", "--output", help="campaign file (default: the scene's name with _campaign.h5)")


def parse_limits(text, chans) -> dict:
    out = {}
    for item in (text or "").split(","):
        if not item.strip():
            continue
        if "=" not in item:
            raise InputError(f"--limits {item.strip()!r}: expected KEY=VALUE")
        k, v = (x.strip() for x in item.split("=", 1))
        if k not in chans:
            raise InputError(f"--limits {k}: not a channel of this scene ({', '.join(chans)})")
        try:
            x = float(v)
        except ValueError:
            raise InputError(f"--limits {k}: {v!r} is not a number") from None
        if not (x > 0 and math.isfinite(x)):
            raise InputError(f"--limits {k}: must be a positive number, got {v}")
        out[k] = x
    return out


def parse_headings(text):
    if text is None:
        return None
    try:
        heads = [float(h) for h in text.split(",") if h.strip()]
    except ValueError:
        raise InputError(f"--headings: expected numbers in rad separated by commas, got {text!r}") from None
    if not heads or not all(math.isfinite(h) for h in heads):
        raise InputError(f"--headings: expected finite numbers in rad, got {text!r}")
    bad = not_radians(heads)
    if bad:
        raise InputError(f"--headings: {bad}")
    return heads


def cmd_campaign(a):
    positive("duration", a.duration)
    if a.seeds is not None and a.seeds < 1:
        raise InputError(f"--seeds: must be at least 1, got {a.seeds}")
    if a.workers is not None and a.workers < 1:
        raise InputError(f"--workers: must be at least 1, got {a.workers}")
    if a.batch < 1:
        raise InputError(f"--batch: must be at least 1, got {a.batch}")
    if not os.path.isfile(a.scatter):
        raise InputError(f"--scatter: {a.scatter}: no such file")
    scene = load(a.scene)
    heads = parse_headings(a.headings)
    limits = parse_limits(a.limits, channel_names(scene)) if a.limits is not None else None   # None: the scene's
    out = a.output or os.path.splitext(os.path.basename(a.scene))[0] + "_campaign.h5"
    writable_output("-o", out, inputs=(a.scene, a.scatter))
    if a.resume and not os.path.exists(out):
        print(f"warning: --resume: {out} does not exist yet; starting the campaign", file=sys.stderr)
    setup_jax()
    client = None
    if a.scheduler:
        from dask.distributed import Client      # Dask imported only where a cluster is used
        try:
            client = Client(a.scheduler, timeout=30)
        except (OSError, TimeoutError) as e:
            raise InputError(f"--scheduler {a.scheduler}: cannot connect ({' '.join(str(e).split())})") from None
    try:
        r = campaign(scene, a.scatter, headings=heads, seeds=a.seeds, duration=a.duration, client=client,
                     output=out, limits=limits, resume=a.resume, workers=a.workers or 2, batch=a.batch,
                     progress=None if not a.no_progress else False)
    except ScatterError as e:
        raise InputError(f"--scatter {a.scatter}: {e}") from None
    except CampaignError as e:
        raise InputError(e.cli) from None
    except ResultFileError as e:
        raise InputError(str(e)) from None
    except OutputError as e:
        raise InputError(f"-o: {e.strerror}") from None
    finally:
        if client is not None:
            client.close()
    report_failures(r.cases, r.status)
    if r.limits:         # none (--limits "", or none in the scene): no table, no operability
        wide = max([12] + [len(ch) for ch in r.limits])      # connection.<name> and the like: longer
        print(f"{'channel':>{wide}} {'limit':>10} {'P(exceed)':>10}")
        for ch, lim in r.limits.items():
            print(f"{ch:>{wide}} {lim:10.4g} {r.exceedance.get(ch, math.nan):10.4g}")
        judged = "" if not r.failed_weight > 0 else \
            f"; {r.failed_weight:.2f} % of it in failed cases, counted as not operable"
        print(f"operability: {r.operability:.2f} % of the scatter's weight within every limit{judged}")
    print(f"done: {r.run_now} cases run now, {r.done_before} already done, {r.failed} failed, "
          f"{r.wall:.1f} s wall{phase_text(r.phases)} -> {out}")
    return 0 if r.failed == 0 else 3


#: the campaign's phases as the summary line names them (CampaignResult.phases)
PHASES = (("setup", "cases checked"), ("start", "workers' start"), ("first", "first batch"),
          ("cases", "other batches"), ("write", "of them writing"))


def phase_text(phases: dict) -> str:
    """` (cases checked 0.3 s, workers' start 2.9 s, first batch 4.1 s, other batches 20.2 s, of
    them writing 0.1 s)`: where the wall time went; empty when no case ran."""
    shown = [f"{name} {phases[k]:.1f} s" for k, name in PHASES if k in phases and (k != "start" or phases[k] > 0)]
    return f" ({', '.join(shown)})" if "first" in phases else ""


#: failed cases named one by one up to this many per reason; reasons printed up to SHOW_REASONS
#: (the file's /cases/status holds every one)
SHOW_CASES, SHOW_REASONS = 8, 20


def report_failures(cases, status, stream=None):
    """Each failed case's reason on stderr, the cases that share a reason on one line:
    `failed: case 3 (hs 6 m, tp 8 s, heading 1.571 rad, seed 0): step 78 (t = 7.8 s): Newton ...`."""
    stream = sys.stderr if stream is None else stream
    by_reason: dict = {}
    for i, s in enumerate(status):
        if s not in ("ok", PENDING):
            by_reason.setdefault(s, []).append(i)

    def one(i):
        return (f"case {i} (hs {cases.hs[i]:g} m, tp {cases.tp[i]:g} s, heading {cases.heading[i]:.4g} rad, "
                f"seed {int(cases.seed[i])})")
    reasons = list(by_reason.items())
    for reason, idx in reasons[:SHOW_REASONS]:
        if len(idx) == 1:
            who = one(idx[0])
        else:
            shown = ", ".join(str(i) for i in idx[:SHOW_CASES]) + (", ..." if len(idx) > SHOW_CASES else "")
            who = f"{len(idx)} cases ({shown}; the first: {one(idx[0])})"
        print(f"failed: {who}: {reason}", file=stream)
    if len(reasons) > SHOW_REASONS:
        rest = sum(len(idx) for _, idx in reasons[SHOW_REASONS:])
        print(f"failed: {rest} more cases, each reason in the campaign file's /cases/status", file=stream)
