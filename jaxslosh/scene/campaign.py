"""The `[campaign]` table: operability limits per response channel and the defaults of a campaign
(headings, seeds, duration) kept with the scene, so that a campaign's criteria travel with the ship
they judge. `jaxslosh campaign` and `js.campaign` take them when their own arguments leave them out
(the command line wins); `jaxslosh run` ignores the table.

    [campaign]
    headings = [0.0, 0.785, 1.571]    # rad
    seeds = 2
    duration = 600.0                  # s
    [campaign.limits]                 # channel = limit: rad for roll and pitch, m for heave and probes,
    roll = 0.1                        # N for lines and connections
    "probe.B" = 0.5                   # or probe.B = 0.5 (TOML's dotted key: a table probe = {B = 0.5})
    "mooring.line1" = 2.0e5           # a line's fairlead tension about its mean, N
    "barge.roll" = 0.15               # a [[bodies]] body's roll (also <body>.pitch, <body>.heave)
    "connection.bow_hawser" = 1.0e5   # a [[connections]] connection's force about its mean, N
"""
from __future__ import annotations

import math

from .fields import at_least, flat_list, positive, read, show
from .types import CampaignTable, Probe, SceneError, Waves

#: the channels of every scene; probes add `probe.<name>` (their vertical displacement), mooring
#: lines `mooring.<name>` (their fairlead tension), [[bodies]] `<body>.roll`, `<body>.pitch`,
#: `<body>.heave` and [[connections]] `connection.<name>` (their force, positive when it pulls)
RIGID_CHANNELS = ("roll", "pitch", "heave")
UNITS = {"roll": "rad", "pitch": "rad", "heave": "m"}      # probe.<name>: its vertical displacement, m
#: the prefixes of channels in newtons
FORCE_PREFIXES = ("mooring.", "connection.")


def unit(channel: str) -> str:
    """A channel's unit: rad, m, or N for a mooring line's tension and a connection's force."""
    if channel.startswith(FORCE_PREFIXES):
        return "N"
    head, _, tail = channel.rpartition(".")
    return UNITS.get(tail if head != "probe" else channel, "m")     # <body>.roll as roll


def channels(probes, mooring=(), bodies=(), connections=()) -> list[str]:
    """The response channels of a scene with these probes, mooring lines, bodies and connections:
    roll, pitch, heave, probe.<name>, mooring.<name>, <body>.roll, <body>.pitch, <body>.heave,
    connection.<name>."""
    return (list(RIGID_CHANNELS) + [f"probe.{p.name}" for p in probes]
            + [f"mooring.{m.name}" for m in mooring]
            + [f"{b.name}.{c}" for b in bodies for c in RIGID_CHANNELS]
            + [f"connection.{c.name}" for c in connections])


def read_campaign(table, probes: tuple[Probe, ...], waves: Waves | None, simulation_dt: float,
                  warnings: list[str], mooring=(), bodies=(), connections=()) -> CampaignTable:
    where = "campaign"
    v = read(table, where, {
        "limits": ("table", None), "headings": ("numbers", _headings), "seeds": ("int", at_least(1)),
        "duration": ("float", positive),
    })
    heads = v.get("headings")
    if heads is not None:
        heads = tuple(heads) if isinstance(heads, list) else (heads,)
    duration = v.get("duration")
    if duration is not None and duration < simulation_dt:
        raise SceneError(f"{where}.duration", f"{show(duration)} s is shorter than one step "
                                              f"(simulation.dt = {show(simulation_dt)} s)")
    irregular = waves is not None and waves.irregular
    if duration is not None and irregular and duration <= waves.ramp:
        raise SceneError(f"{where}.duration", f"{show(duration)} s is not longer than waves.ramp = "
                                              f"{show(waves.ramp)} s: a campaign's statistics are over the frames "
                                              f"after the ramp")
    if not irregular:
        warnings.append('campaign: the [campaign] table is for `jaxslosh campaign`, whose template is an irregular '
                        '[waves] table (type = "jonswap" or "pierson-moskowitz"); this scene has none, and '
                        '`jaxslosh run` ignores the table')
    chans = channels(probes, mooring, bodies, connections)
    limits = _limits(table["limits"], f"{where}.limits", chans) if "limits" in table else ()
    return CampaignTable(limits=limits, headings=heads, seeds=v.get("seeds"), duration=duration)


def _headings(v):
    return flat_list(v, "a heading in rad")[1] or not_radians(v if isinstance(v, list) else [v])


def not_radians(headings) -> str | None:
    """None, or the message for headings beyond 2 pi: degrees typed where radians are asked for
    (90 would be taken as 90 rad, 14.3 turns)."""
    big = [h for h in headings if isinstance(h, (int, float)) and abs(h) > 2.0 * math.pi + 1e-9]
    if not big:
        return None
    shown = ", ".join(f"{h:g}" for h in big)
    return (f"{shown} {'is' if len(big) == 1 else 'are'} beyond 2 pi: headings are in radians "
            f"({big[0]:g} deg = {math.radians(big[0]):.6g} rad)")


def _limits(table, where: str, chans: list[str]) -> tuple[tuple[str, float], ...]:
    """{channel: limit} as written; `probe.B = 0.5` (a dotted key, which TOML reads as a table
    probe = {B = 0.5}) and `"probe.B" = 0.5` (a quoted key) name the same channel (so do
    `mooring.line1` and `"mooring.line1"`, `barge.roll` and `"barge.roll"`)."""
    if not isinstance(table, dict):
        raise SceneError(where, f"must be a table of channel = limit ({', '.join(chans)}), got {show(table)}")
    flat: dict = {}
    for key, value in table.items():      # a limit is a number: a table is a dotted key's first part
        items = [(f"{key}.{k}", x) for k, x in value.items()] if isinstance(value, dict) else [(key, value)]
        for ch, x in items:
            if ch in flat:
                raise SceneError(f"{where}.{ch}", "is given twice (as a quoted key and as a dotted key)")
            if ch not in chans:
                raise SceneError(f"{where}.{ch}", f"not a channel of this scene (channels: {', '.join(chans)})")
            flat[ch] = x
    spec = {ch: ("float", _positive_limit(unit(ch))) for ch in flat}
    out = read(flat, where, spec)
    return tuple((ch, out[ch]) for ch in flat)


def _positive_limit(unit: str):
    return lambda x: None if x > 0 and math.isfinite(x) else f"must be a positive limit in {unit}, got {show(x)}"

