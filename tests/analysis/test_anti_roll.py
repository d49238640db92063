"""A flume-type passive anti-roll tank (issue 18, item 6; scenes/anti_roll_tank.toml): in regular
beam waves at the ship's roll resonance, the steady roll with the tank's liquid sloshing (tuned to
the roll, damped) is at most half the roll of the same ship with that liquid frozen.

Frozen: the same scene with `[effects] liquid = false`, which drops the liquid altogether, so its
mass and its inertia about the COG are added to the vessel's (params), as notebooks/waves.ipynb
does. Steady amplitudes: a least-squares fit of cos, sin and a constant at the wave frequency over
the last PERIODS wave periods; the PERIODS before them must give the same amplitude (the transient
is gone). `pytest tests/analysis/test_anti_roll.py -s` prints the amplitudes and their ratio."""
import time
from pathlib import Path

import numpy as np

import jaxslosh as js

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "anti_roll_tank.toml"
PERIODS = 5


def frozen_params(scene) -> dict:
    """The vessel's mass and inertia (about the COG, the frame origin) with every tank's liquid
    added as a rigid body: the liquid at rest, a box of fluid of the fill depth."""
    mass = scene.vessel.mass
    inertia = np.asarray(scene.vessel.inertia, dtype=float)
    inertia = np.diag(inertia) if inertia.ndim == 1 else inertia
    for t in scene.tanks:
        assert t.shape == "box" and not t.baffles, "the frozen liquid's inertia below is a box's"
        m = t.liquid_mass
        a, b, h = t.size[0], t.size[1], t.fill_depth
        c = np.asarray(t.origin) + np.array([a, b, h]) / 2          # the liquid's centroid, vessel frame
        own = m / 12 * np.diag([b * b + h * h, a * a + h * h, a * a + b * b])
        inertia = inertia + own + m * (c @ c * np.eye(3) - np.outer(c, c))    # parallel axes
        mass = mass + m
    return {"vessel.mass": float(mass), "vessel.inertia": inertia.tolist()}


def steady_amplitude(result, omega: float, periods: int, skip: int = 0) -> float:
    """Amplitude of the roll's harmonic at omega over `periods` periods, ending `skip` periods
    before the run's end."""
    t = np.asarray(result.time)
    roll = np.asarray(result.vessel.roll_pitch_yaw[:, 0])
    T = 2 * np.pi / omega
    end = t[-1] - skip * T
    k = (t > end - periods * T - 1e-9) & (t <= end + 1e-9)
    A = np.stack([np.cos(omega * t[k]), np.sin(omega * t[k]), np.ones(k.sum())], axis=1)
    c = np.linalg.lstsq(A, roll[k], rcond=None)[0]
    return float(np.hypot(c[0], c[1]))


def sloshing_amplitude(result, omega: float, periods: int) -> float:
    """Amplitude of the free surface at the port wall relative to the tank (probe 'surface' less
    the wall's foot below it), over the last `periods` periods."""
    t = np.asarray(result.time)
    rel = np.asarray(result.probes["surface"].displacement[:, 2] - result.probes["wall"].displacement[:, 2])
    k = t > t[-1] - periods * 2 * np.pi / omega - 1e-9
    A = np.stack([np.cos(omega * t[k]), np.sin(omega * t[k]), np.ones(k.sum())], axis=1)
    c = np.linalg.lstsq(A, rel[k], rcond=None)[0]
    return float(np.hypot(c[0], c[1]))


def test_anti_roll_tank_halves_resonant_roll():
    t0 = time.perf_counter()
    scene = js.load_scene(SCENE)
    w, amplitude = scene.waves.omega, scene.waves.amplitude
    frozen_scene = js.load_scene(scene.text + "\n[effects]\nliquid = false\n")
    frozen_p = frozen_params(scene)

    active = js.simulate(scene)
    frozen = js.simulate(frozen_scene, params=frozen_p)
    assert active.status == "ok", active.status
    assert frozen.status == "ok", frozen.status

    roll_active = steady_amplitude(active, w, PERIODS)
    roll_frozen = steady_amplitude(frozen, w, PERIODS)
    # steady: the PERIODS before the last give the same amplitude (the frozen roll's transient
    # decays as exp(-0.029 t), by 0.39 over five periods)
    before_active = steady_amplitude(active, w, PERIODS, skip=PERIODS)
    before_frozen = steady_amplitude(frozen, w, PERIODS, skip=PERIODS)
    assert abs(before_active / roll_active - 1) < 0.01, (before_active, roll_active)
    assert abs(before_frozen / roll_frozen - 1) < 0.01, (before_frozen, roll_frozen)

    # the frozen ship is at its roll resonance: the linear frequency-domain RAO of the frozen scene
    # peaks at the wave frequency, and the time domain's steady roll is that RAO's
    near = np.array([w - 0.01, w, w + 0.01])
    rao = np.abs(js.rao(frozen_scene, near, [scene.waves.heading], params=frozen_p).vessel[:, 0, 3])
    assert rao[1] > rao[0] and rao[1] > rao[2], rao
    assert abs(roll_frozen / (rao[1] * amplitude) - 1) < 0.02, (roll_frozen, rao[1] * amplitude)

    ratio = roll_active / roll_frozen
    slosh = sloshing_amplitude(active, w, PERIODS)
    print(f"\nanti-roll tank at {w:g} rad/s, waves {amplitude:g} m from the beam: steady roll "
          f"{roll_active:.6f} rad ({np.degrees(roll_active):.3f} deg) with the tank active, "
          f"{roll_frozen:.6f} rad ({np.degrees(roll_frozen):.3f} deg) with its liquid frozen "
          f"(frozen RAO x amplitude {rao[1] * amplitude:.6f} rad); ratio {ratio:.3f}; "
          f"free surface at the port wall {slosh:.4f} m relative to the tank; "
          f"{time.perf_counter() - t0:.1f} s")
    assert ratio <= 0.5, ratio
