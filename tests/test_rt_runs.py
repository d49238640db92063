"""Runs of the face-normal liquid element "rt" (issue 30, fem/liquid_rt.py) beyond the plain
reduced run of tests/test_liquid_element_rt.py: modal damping (`[tanks.damping]`) on its sloshing
modes, the U-tube's exchange in a forced roll near its frequency against an independent linear
theory (tests/u_tube_response.py), the default element, and rao / sweep on an rt tank."""
import math
import os
import sys

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.build.damping import build_damping
from jaxslosh.build.liquid import build_liquid_block
from jaxslosh.fem.damping import rectangular_ratio

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_damping import HELD, decrement, free_decay, target  # noqa: E402

RT = '[tanks.fluid]\nelement = "rt"\n[tanks.reduction]\nmodes = 6\n'


def held_rt(extra="", duration=7.0, dt=0.01):
    return js.load_scene(HELD.format(duration=duration, dt=dt, scheme="newmark", alpha=0.0) + RT + extra)


def test_free_decay_of_an_rt_tank_has_the_decrement_of_its_ratio():
    """ratio = 0.02 on the first sloshing mode of the held 1.0 x 0.4 m tank (8 x 2 x 4, "rt" on 6
    modes), trapezoidal rule: the corner's heave decays with 2 pi 0.02 / sqrt(1 - 0.02^2) within 3 %;
    the undamped run's decrement is below 1 % of it."""
    t, z, omega, mode = free_decay(held_rt("[tanks.damping]\nratio = [0.02]\n"))
    assert 5.0 < omega < 5.6
    assert abs(decrement(z) / target(0.02) - 1) < 0.03, decrement(z)
    _, z0, _, _ = free_decay(held_rt(), mode=mode)
    assert abs(decrement(z0)) < 0.01 * target(0.02), decrement(z0)


def test_rt_boundary_layer_ratio_against_the_closed_form():
    """The laminar boundary-layer ratio of the first mode from the rt element's own wall field
    (fem/damping.py) against the rectangular tank's closed form within 3 % (8 x 2 x 4) and 1 %
    (16 x 4 x 8); a ratio adds to it; every mode of the basis that is sloshing is damped."""
    closed = rectangular_ratio(1.0, 0.4, 0.5, 9.81, 1e-6)
    for mesh, tol in (([8, 2, 4], 0.03), ([16, 4, 8], 0.01)):
        text = HELD.format(duration=1.0, dt=0.01, scheme="newmark", alpha=0.0).replace("[8, 2, 4]", str(mesh))
        scene = js.load_scene(text + RT + "[tanks.damping]\nratio = 0.01\nviscosity = 1e-6\n")
        damping, table = build_damping(scene, None, build_liquid_block(scene, None, 9.81))
        zeta = np.asarray(table[0].zeta)
        assert abs((zeta[0] - 0.01) / closed - 1) < tol, (mesh, zeta[0], closed)
        assert len(zeta) == 6 and np.all(zeta > 0.01)
        assert damping.B.shape[0] > 6            # the basis: 6 modes, the static correction, circulation
