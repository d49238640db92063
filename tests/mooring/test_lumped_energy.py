"""A lumped line's energies (jaxslosh/mooring/lumped.py `energies`, the dissipated and fairlead
work its states carry): the balance kinetic + added kinetic + elastic + weight + seabed
+ dissipated - fairlead work = its start, checked where the scheme is first order (symplectic Euler
in the sub-step): its error halves as the sub-step halves, undamped with the fairlead held, damped,
and with the fairlead driven; the powers are summed independently of the scheme's own work terms."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxslosh.io.line_energy import LINE_ENERGY
from jaxslosh.mooring import lumped as lm
from lumped_reference import OC3

F0 = jnp.array(OC3["fairlead"])
ZERO = jnp.zeros(3)
H = 0.1            # the ship's step
STEPS = 50         # 5 s


def line(damped, **kw):
    """The OC3-Hywind line in 20 segments with isotropic added mass (ca normal = tangential: the
    balance is exact in the limit), undamped (no drag, internal or seabed damping) or damped."""
    c = OC3
    off = {} if damped else dict(cd=(0.0, 0.0), internal_damping=0.0, seabed_damping=0.0)
    return lm.lumped_line(c["anchor"], c["length"], c["weight"], c["ea"], segments=20, diameter=c["diameter"],
                          mass=c["mass"], seabed_z=-c["depth"], ca=(1.0, 1.0), **dict(off, **kw))


def stretched(ln):
    """The static shape, every moving node moved 0.2 % further from the anchor (the fairlead held):
    the segments stretched, the last one slackened, the line released from rest."""
    r, ok = lm.static_shape(ln, F0)
    assert bool(ok)
    return lm.LineState(ln.anchor + 1.002 * (r - ln.anchor), jnp.zeros_like(r))


def fairlead(t, amp):
    """A fairlead surging amp sin(0.8 t) (its position and velocity)."""
    e = jnp.array([1.0, 0.0, 0.0])
    return F0 + amp * jnp.sin(0.8 * t) * e, amp * 0.8 * jnp.cos(0.8 * t) * e


def balance_error(ln, s0, factor, amp=0.0):
    """max |E + dissipated - fairlead work - E0| over the run, sub-stepped `factor` times finer
    than the line's own choice, and the largest kinetic energy (with the water's) on the way."""
    k = factor * ln.substeps(H)

    def total(s, t):
        p, _ = fairlead(t, amp)
        return sum(lm.energies(ln, s.r, s.v, p).values()) + s.dissipated - s.work

    def body(s, t):
        p0, v0 = fairlead(t, amp)
        p1, v1 = fairlead(t + H, amp)
        s = lm.advance(ln, s, p0, v0, p1, v1, H, k)
        return s, (total(s, t + H), lm.kinetic(ln, s.r, s.v, p1))

    _, (E, K) = jax.jit(lambda s: jax.lax.scan(body, s, jnp.arange(STEPS) * H))(s0)
    return float(jnp.max(jnp.abs(E - total(s0, 0.0)))), float(jnp.max(K))


@pytest.mark.parametrize("damped, amp", [(False, 0.0), (True, 0.0), (True, 2.0)],
                         ids=["undamped", "damped", "driven"])
def test_balance_is_first_order_in_the_substep(damped, amp):
    ln = line(damped)
    s0 = stretched(ln)
    errs = [balance_error(ln, s0, f, amp) for f in (4, 8, 16)]
    e, K = [x[0] for x in errs], errs[-1][1]
    # the scheme is first order: each halving of the sub-step about halves the error (at the line's
    # own sub-step, half its stability limit, the axial modes' omega dt is 1: the error is then some
    # half of the energy exchanged, 3 % at a sixteenth of it)
    for a, b in zip(e, e[1:]):
        assert 1.6 < a / b < 2.5, e
    assert e[-1] < 0.05 * K, (e, K)


def test_dissipated_work_is_the_damping_power_integrated():
    """The dissipated work after one step equals the damping's power summed over the sub-steps on
    the host, each at the sub-step's start. With the fairlead held and no current, the damping
    forces (internal damping, drag, seabed damping) are the nodes' net force less the same at zero
    velocity, and the net force is the node mass times the acceleration (isotropic added mass): the
    power is -sum v . m (a(r, v) - a(r, 0)), from `accelerations` alone."""
    ln = line(True)
    s0 = stretched(ln)._replace(v=0.05 * jnp.ones((19, 3)))
    k = ln.substeps(H)
    s1 = lm.advance(ln, s0, F0, ZERO, F0, ZERO, H, k)
    dt = H / k
    m = float(ln.mass * ln.seg + ln.rho * jnp.pi * ln.diameter ** 2 / 4 * ln.seg * ln.ca[0])
    acc = jax.jit(lambda r, v: lm.accelerations(ln, r, v, F0, ZERO))
    r, v, lost = s0.r, s0.v, 0.0
    for _ in range(k):         # the reference: the sub-steps one by one on the host
        a = acc(r, v)
        lost += dt * -m * float(jnp.sum(v * (a - acc(r, jnp.zeros_like(v)))))
        v = v + dt * a
        r = r + dt * v
    assert lost > 0
    assert float(s1.dissipated) == pytest.approx(lost, rel=1e-9)
    assert float(s1.work) == 0.0


def test_energy_parts_are_the_result_files():
    assert set(lm.energies(line(False), *stretched(line(False))[:2], F0)) | {"dissipated", "fairlead_work"} \
        == set(LINE_ENERGY)


@pytest.mark.slow
def test_run_writes_the_energies(tmp_path):
    """`jaxslosh run` on a barge on three lumped lines writes each line's energies, in J, with their
    descriptions; `js.load_result` reads them back; they start at rest (no kinetic energy, no work
    yet) and the balance holds to the scheme's first-order error at the line's own sub-step."""
    import h5py
    from jaxslosh.cli.main import main
    from test_lumped_scene import LUMPED
    from test_statics import SMALL, _lines
    scene = tmp_path / "moored.toml"
    scene.write_text(SMALL.replace("duration = 60.0", "duration = 2.0") + _lines(extra=LUMPED))
    out = tmp_path / "moored.h5"
    assert main(["run", str(scene), "-o", str(out)]) == 0
    with h5py.File(out) as f:
        for k in LINE_ENERGY:
            ds = f[f"energy/mooring/l0/{k}"]
            assert ds.attrs["units"] == "J" and ds.attrs["description"] == LINE_ENERGY[k]
            assert ds.shape == f["time"].shape
    m = __import__("jaxslosh").load_result(str(out)).mooring["l1"]
    e = {k: np.asarray(v) for k, v in m.energy.items()}
    assert e["kinetic"][0] == 0.0 and e["dissipated"][0] == 0.0 and e["fairlead_work"][0] == 0.0
    assert e["elastic"][0] > 0 and np.all(e["dissipated"][1:] > 0)
    E = sum(e[k] for k in LINE_ENERGY if k not in ("dissipated", "fairlead_work")) + e["dissipated"] - e["fairlead_work"]
    # measured: 7.7 J against the fairlead's 5,726 J over 2 s (the ship's step 0.2 s, 5 sub-steps)
    assert np.max(np.abs(E - E[0])) < 5e-3 * np.max(np.abs(e["fairlead_work"]))


def test_result_file_keeps_the_energies(tmp_path):
    """The energies through `js.save_result` and `js.load_result`: the same arrays, in J; a
    catenary line beside it has none (and a file without them reads as before)."""
    import h5py
    import jaxslosh as js
    from jaxslosh.io.result import result_from, result_frames
    n = 4
    d = {"time": np.arange(n) * 0.1, "vessel/position": np.zeros((n, 3)), "vessel/quaternion": np.tile([1.0, 0, 0, 0], (n, 1)),
         "vessel/angular_velocity": np.zeros((n, 3)), "vessel/roll_pitch_yaw": np.zeros((n, 3)),
         "energy/kinetic": np.ones(n), "energy/potential": np.ones(n), "solver/iterations": np.ones(n, int),
         "solver/residual": np.zeros(n), "solver/constraint": np.zeros(n)}
    for name in ("lumped", "catenary"):
        d[f"mooring/{name}/fairlead_tension"] = d[f"mooring/{name}/anchor_tension"] = np.ones(n)
    d["mooring/lumped/nodes"] = np.zeros((n, 3, 3))
    d.update({f"energy/mooring/lumped/{k}": np.arange(n) + i for i, k in enumerate(LINE_ENERGY)})
    path = str(tmp_path / "r.h5")
    js.save_result(result_from(d), path)
    back = js.load_result(path)
    assert back.mooring["catenary"].energy is None
    for i, k in enumerate(LINE_ENERGY):
        np.testing.assert_array_equal(np.asarray(back.mooring["lumped"].energy[k]), np.arange(n) + i)
    assert set(result_frames(back)) == set(d)
    with h5py.File(path) as f:
        assert f["energy/mooring/lumped/elastic"].attrs["units"] == "J"
        assert f["energy/mooring/lumped/elastic"].attrs["description"] == LINE_ENERGY["elastic"]
