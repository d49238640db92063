"""Small scenes and measurements shared by the tests."""
from __future__ import annotations

import numpy as np

import jaxslosh as js

VESSEL = """
title = "test vessel"
[environment]
gravity = 9.81
water_density = 1025.0
[simulation]
duration = {duration}
dt = {dt}
scheme = "{scheme}"
alpha = {alpha}
[vessel]
mass = 4.0e5
inertia = [5.0e6, 1.5e7, 1.7e7]
[vessel.hydrostatics]
waterplane_area = 200.0
displaced_volume = 390.0
gm_t = 1.5
gm_l = 15.0
[vessel.initial]
angular_velocity = {omega}
position = {position}
"""


def vessel_scene(duration=10.0, dt=0.01, scheme="hht", alpha=0.01, omega=(0.0, 0.0, 0.0), position=(0.0, 0.0, 0.0),
                 extra=""):
    text = VESSEL.format(duration=duration, dt=dt, scheme=scheme, alpha=alpha, omega=list(omega),
                         position=list(position)) + extra
    return js.load_scene(text)


def zero_crossing_period(t, x):
    """Mean period from upward zero crossings (linear interpolation between samples)."""
    t, x = np.asarray(t), np.asarray(x)
    i = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    tc = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    assert len(tc) >= 3, "too few oscillations to measure a period"
    return (tc[-1] - tc[0]) / (len(tc) - 1)
