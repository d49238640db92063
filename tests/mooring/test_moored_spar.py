"""OC3-Hywind with a tuned liquid damper (scenes/oc3_hywind_tld.toml): the tank's first sloshing
frequency against the spar's pitch natural frequency, and the gradient of a line-tension statistic
with respect to a line's length (notebooks/moored_spar.ipynb, docs/guide/moorings.md)."""
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.analysis.coupled import coupled_modes

ROOT = Path(__file__).resolve().parents[2]
PLAIN = ROOT / "scenes" / "oc3_hywind.toml"
TLD = ROOT / "scenes" / "oc3_hywind_tld.toml"


def _tank_closed_form(scene):
    """omega^2 = g k tanh(k h), k = pi / L: the tank's first mode along its length."""
    t = scene.tanks[0]
    k = np.pi / t.size[0]
    return np.sqrt(scene.environment.gravity * k * np.tanh(k * t.fill_depth))


def test_the_tank_is_tuned_to_the_spars_pitch_frequency():
    """The pitch frequency in closed form: sqrt((C55 + K55) / I55), C55 = rho g V GM_L the
    hydrostatic restoring and K55 = -3.24e6 N m/rad the lines' about the COG (`jaxslosh mooring`,
    checked in test_statics.py); the tank's closed form within 0.5 % of it. The plain scene's mass
    is the tank scene's plus the tank's water."""
    plain, tld = js.load_scene(str(PLAIN)), js.load_scene(str(TLD))
    env, h = plain.environment, plain.vessel.hydrostatics
    c55 = env.water_density * env.gravity * h.displaced_volume * h.gm_l
    pitch = np.sqrt((c55 - 3.24e6) / np.asarray(plain.vessel.inertia)[1, 1])
    assert abs(pitch - 0.24707) < 2e-4                     # what `jaxslosh modes --coupled` prints
    assert abs(_tank_closed_form(tld) / pitch - 1) < 0.005
    t = tld.tanks[0]
    water = t.fluid.density * t.size[0] * t.size[1] * t.fill_depth
    assert abs(tld.vessel.mass + water - plain.vessel.mass) < 1.0


@pytest.mark.slow          # about a minute: the coupled modes' linearisation of the spar
def test_the_tanks_finite_elements_and_the_coupled_pitch_mode_agree():
    plain, tld = js.load_scene(str(PLAIN)), js.load_scene(str(TLD))
    slosh = float(np.asarray(js.sloshing_modes(tld, n=2).omega)[0])
    modes = coupled_modes(plain, n=6)
    w = np.asarray(modes.omega)
    pitch = float(w[[i for i, d in enumerate(modes.dominant) if d == "pitch"][0]])
    assert abs(slosh / _tank_closed_form(tld) - 1) < 0.005      # the mesh: +0.32 %
    assert abs(slosh / pitch - 1) < 0.01


@pytest.mark.slow          # about 90 s on a shared 2-core machine: three compiled runs
def test_gradient_of_the_mean_fairlead_tension_in_a_lines_length():
    """The plain spar's surge free decay from 2 m, 10 s: d(mean fairlead tension of line1)/d(its
    length) by jax.grad through the run against a central difference."""
    scene = js.load_scene(PLAIN.read_text().replace("duration = 200.0", "duration = 10.0")
                          .replace("dt = 0.25", "dt = 0.5"))

    def mean_tension(length):
        r = js.simulate(scene, params={"mooring.line1.length": length})
        return jnp.mean(r.mooring["line1"].fairlead_tension)

    L = 902.2
    g = float(jax.grad(mean_tension)(L))
    h = 0.01
    fd = (float(mean_tension(L + h)) - float(mean_tension(L - h))) / (2 * h)
    assert g == pytest.approx(fd, rel=1e-5)
    assert g < -1e3            # N/m: a longer line hangs slacker
