"""Three-dimensional multimodal tanks in a scene (`flow = "3d"` boxes, upright cylinders): forced at
small amplitude against the linear theory's closed forms, carried by a free vessel with its energy
conserved, their keys; and a square base's planar waves turning into swirl near resonance."""
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import special

import jaxslosh as js
from jaxslosh.liquid.multimodal.tank3d import box_tank3d

G = 9.81
FORCED = """
[environment]
gravity = 9.81
[simulation]
duration = {duration}
dt = {dt}
scheme = "newmark"
[vessel]
mass = 1.0e4
inertia = [1.0e4, 1.0e4, 1.0e4]
[vessel.forced]
dof = "surge"
amplitude = {amplitude}
frequency = {w}
ramp = 2.0
[[tanks]]
name = "tank"
origin = [-0.5, -0.5, -0.3]
size = [1.0, 1.0, 0.8]
fill_depth = 0.5
model = "multimodal"
{shape}
modes = 5
[tanks.damping]
ratio = {ratio}
[[probes]]
name = "wall"
tank = "tank"
point = [0.0, 0.5, 0.5]
[[probes]]
name = "side"
tank = "tank"
point = [0.5, 0.0, 0.5]
"""
BOX, CYLINDER = 'flow = "3d"', 'shape = "cylinder"\naxis = "z"'


def _amplitude(t, z, w, t0):
    m = t > t0
    A = np.stack([np.cos(w * t[m]), np.sin(w * t[m]), np.ones(m.sum())], axis=1)
    a, b, _ = np.linalg.lstsq(A, z[m], rcond=None)[0]
    return np.hypot(a, b)


def _transfer(shape, w, zeta, h=0.5):
    """Linear theory: the wall elevation on the surge axis per unit surge amplitude, the one mode that
    surge drives (cos(pi x / L) on the unit square; J_1(k r) cos(theta) / J_1(k R) in the cylinder of
    radius 1/2, k R = j'_11): lambda w^2 / (mu |w_1^2 - w^2 + 2 i zeta w_1 w|), lambda the mode's
    integral of x over the base, mu its modal mass per density."""
    if shape == BOX:
        k = np.pi
        lam, norm = 2.0 / np.pi ** 2, 0.5
    else:
        R = 0.5
        k = special.jnp_zeros(1, 1)[0] / R
        lam = np.pi * R ** 2 * special.jv(2, k * R) / (k * special.jv(1, k * R))
        norm = 0.5 * np.pi * R ** 2 * (1.0 - 1.0 / (k * R) ** 2)
    w1 = np.sqrt(G * k * np.tanh(k * h))
    mu = norm / (k * np.tanh(k * h))
    return abs(lam * w ** 2 / (mu * (w1 ** 2 - w ** 2 + 2j * zeta * w1 * w)))


@pytest.mark.slow        # the three-dimensional system's compile (half a minute); its linear frequencies are checked quickly
@pytest.mark.parametrize("shape, dt", [(BOX, 0.04), (CYLINDER, 0.02)])
def test_forced_small_amplitude_is_linear_theory(shape, dt):
    """1 mm of surge: the steady elevation at the wall on the surge axis is linear theory's; the wall
    across (y = 0) barely moves. (The box at dt = 0.04 s, 40 steps a forcing period: the
    trapezoidal rule's error, of order (w dt)^2 / 12 = 0.2 %, stays inside the 1 %.)"""
    w = 4.0
    r = js.simulate(js.load_scene(FORCED.format(duration=7.0, dt=dt, amplitude=0.001, w=w, ratio=0.4, shape=shape)))
    assert r.status == "ok"
    t, z = np.asarray(r.time), np.asarray(r.probes["wall"].displacement)[:, 2]
    amp = _amplitude(t, z, w, 4.5)
    assert amp == pytest.approx(0.001 * _transfer(shape, w, 0.4), rel=1e-2)
    side = np.asarray(r.probes["side"].displacement)[:, 2]
    assert np.abs(side[t > 4.5]).max() < 0.05 * amp


FREE = """
[environment]
gravity = 9.81
[simulation]
duration = {duration}
dt = 0.01
scheme = "newmark"
[vessel]
mass = 2.0e4
inertia = [2.0e4, 4.0e4, 4.0e4]
[vessel.hydrostatics]
waterplane_area = 20.0
displaced_volume = 21.5
gm_t = 1.0
gm_l = 3.0
[vessel.initial]
angular_velocity = [0.03, 0.05, 0.02]
velocity = [0.1, 0.05, 0.0]
[[tanks]]
name = "tank"
origin = [-0.8, -0.6, 0.0]
size = [1.6, 1.2, 1.2]
fill_depth = 0.6
model = "multimodal"
{shape}
modes = 5
[[probes]]
name = "wall"
tank = "tank"
point = [0.0, 0.6, 0.6]
"""


@pytest.mark.slow
@pytest.mark.parametrize("shape", [BOX, 'shape = "cylinder"\naxis = "z"\n'])
def test_free_vessel_conserves_energy(shape):
    """Newmark, no damping: the total energy of the vessel and its liquid sloshing in three dimensions
    stays constant over 10 sloshing periods."""
    text = FREE.format(duration=12.0, shape=shape)
    if "cylinder" in shape:
        text = text.replace("size = [1.6, 1.2, 1.2]", "size = [1.2, 1.2, 1.2]").replace("-0.8, -0.6", "-0.6, -0.6")
    r = js.simulate(js.load_scene(text))
    assert r.status == "ok"
    E = np.asarray(r.energy.kinetic) + np.asarray(r.energy.potential)
    z = np.asarray(r.probes["wall"].displacement)[:, 2]
    assert np.abs(z).max() > 0.005                       # the liquid sloshes
    assert np.abs(E - E[0]).max() <= 1e-4 * E[0]


def test_keys():
    base = FORCED.format(duration=1.0, dt=0.02, amplitude=0.001, w=4.0, ratio=0.1, shape=CYLINDER)
    s = js.load_scene(base)
    assert s.tanks[0].flow == "3d" and s.tanks[0].shape == "cylinder"
    assert js.load_scene(FORCED.format(duration=1.0, dt=0.02, amplitude=0.001, w=4.0, ratio=0.1, shape="")).tanks[0].flow == "2d"
    with pytest.raises(js.SceneError, match=r"tanks\[0\]\.flow"):
        js.load_scene(base.replace('axis = "z"', 'axis = "z"\nflow = "2d"'))
    with pytest.raises(js.SceneError, match=r"tanks\[0\]\.axis"):
        js.load_scene(base.replace('axis = "z"', 'axis = "x"'))
    with pytest.raises(js.SceneError, match=r"tanks\[0\]\.flow"):
        js.load_scene(FORCED.format(duration=1.0, dt=0.02, amplitude=0.001, w=4.0, ratio=0.1, shape=BOX)
                      .replace('model = "multimodal"\n', 'mesh = [2, 2, 2]\n').replace("modes = 5\n", ""))


@eqx.filter_jit
def _forced_surge(t, sig, amp, periods, per=24):
    """The modal rows alone (RK4) under a surge x = amp cos(sig t), no damping, from a level surface
    with a 1e-4 m seed of the cross mode (0, 1): (periods * per, N) amplitudes."""
    n = t.n
    z = jnp.zeros(n)
    dt = 2 * jnp.pi / sig / per
    Z3, gb = jnp.zeros(3), jnp.array([0.0, 0.0, -G])

    def acc(y, s):
        be, bd = y[:n], y[n:]
        a = jnp.array([-amp * sig ** 2 * jnp.cos(sig * s), 0.0, 0.0])
        r = lambda x: t.rows(Z3, Z3, be, bd, a, Z3, x, gb)[2]  # noqa: E731
        return jnp.concatenate([bd, -jnp.linalg.solve(jax.jacfwd(r)(z), r(z))])

    def step(y, i):
        s = i * dt
        k1 = acc(y, s)
        k2 = acc(y + dt / 2 * k1, s + dt / 2)
        k3 = acc(y + dt / 2 * k2, s + dt / 2)
        k4 = acc(y + dt * k3, s + dt)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return y, y[:n]
    _, b = jax.lax.scan(step, jnp.concatenate([z.at[1].set(1e-4), z]), jnp.arange(periods * per))
    return b


@pytest.mark.slow
def test_square_base_forced_along_x_swirls_at_resonance():
    """A square base (h / L = 0.5) forced along x by 0.005 L: at the first resonance the planar wave
    is unstable (the band of Faltinsen, Rognebakke & Timokha 2003, J. Fluid Mech. 487, where neither
    planar steady-state solution is stable) and the cross mode grows from its 1e-4 m seed to the
    planar mode's order (swirl); at 0.8 of the resonance it stays at its seed."""
    t = box_tank3d(1.0, 1.0, 0.5, 1000.0, (-0.5, -0.5, -0.2), 5, D=1.0)
    w1 = float(t.omega_linear(G)[0])
    near = np.asarray(_forced_surge(t, w1, 0.005, 40))
    below = np.asarray(_forced_surge(t, 0.8 * w1, 0.005, 40))
    assert np.abs(near[:, 1]).max() > 0.3 * np.abs(near[:, 0]).max()
    assert np.abs(near[:, 1]).max() > 100 * 1e-4
    assert np.abs(below[:, 1]).max() < 2e-4
    assert np.abs(below[:, 0]).max() > 0.01


@pytest.mark.slow      # minutes of CPU on 2 cores: kept out of the default suite
def test_gradient_through_a_run_with_a_3d_tank_matches_finite_differences():
    """The gradient of a corner's elevation after 10 steps of a free vessel carrying a `flow = "3d"`
    box (its lowest pair of modes, across and along), with respect to the fill depth, by the implicit
    function theorem through every Newton solve, against central differences."""
    text = FREE.format(duration=0.1, shape=BOX).replace("modes = 5", "modes = 2").replace(
        "point = [0.0, 0.6, 0.6]", "point = [0.0, 0.0, 0.6]")
    scene = js.load_scene(text)
    run = eqx.filter_jit(lambda h: js.simulate(scene, params={"tanks.tank.fill_depth": h}).probes["wall"]
                         .displacement[-1, 2])
    h = 0.6
    g = float(jax.grad(run)(h))
    eps = 1e-4
    fd = (float(run(h + eps)) - float(run(h - eps))) / (2 * eps)
    assert abs(float(run(h))) > 2e-5                      # the corner moves
    assert g == pytest.approx(fd, rel=1e-4, abs=1e-9)
    assert abs(g) > 1e-5                                  # (-4.6e-5 m per m of depth)
