"""Side by side with Exudyn (C++ floating-frame multibody code): same scene, same step, one run.

    pip install exudyn          # a benchmark-only dependency, not one of jaxslosh's
    python benchmarks/exudyn_compare.py [--duration 20] [--repeat 3]

The vessel alone (scenes/vessel_only.toml) on hydrostatic springs: in Exudyn a rigid body (Euler
parameters) tied to the ground by CreateRigidBodySpringDamper with the heave, roll and pitch
stiffnesses rho g A_w, rho g V GM_T, rho g V GM_L and useIntrinsicFormulation=False (its default
intrinsic formulation gives wrong hydrostatics); Exudyn's generalized-alpha with the spectral radius
of our HHT alpha = 0.01, (1 - alpha) / (1 + alpha). Prints steps per second of both and the largest
difference of roll, pitch and heave over the run.

Not done here (see README): the paper's liquid as an ObjectFFRFreducedOrder and an ObjectFFRF body
built from our mass and stiffness matrices.
"""
import argparse
import os
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

import jaxslosh as js  # noqa: E402
from jaxslosh.run import _core, advance, prepare, start  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def exudyn_barge(scene, duration, dt):
    import exudyn as exu
    from exudyn.utilities import RigidBodyInertia, SensorBody
    v, h, env = scene.vessel, scene.vessel.hydrostatics, scene.environment
    rho_g = env.water_density * env.gravity
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.CreateGround(referencePosition=[0, 0, 0])
    body = mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=v.mass, inertiaTensor=np.asarray(v.inertia)),
                               referencePosition=[0, 0, 0], initialVelocity=list(v.initial.velocity),
                               initialAngularVelocity=list(v.initial.angular_velocity), gravity=[0, 0, 0])
    k = np.diag([0.0, 0.0, rho_g * h.waterplane_area, rho_g * h.displaced_volume * h.gm_t,
                 rho_g * h.displaced_volume * h.gm_l, 0.0])
    mbs.CreateRigidBodySpringDamper(itemNumbers=[ground, body], stiffness=k, damping=np.zeros((6, 6)),
                                    useIntrinsicFormulation=False)
    s_pos = mbs.AddSensor(SensorBody(bodyNumber=body, outputVariableType=exu.OutputVariableType.Position,
                                     storeInternal=True))
    s_rot = mbs.AddSensor(SensorBody(bodyNumber=body, outputVariableType=exu.OutputVariableType.Rotation,
                                     storeInternal=True))
    mbs.Assemble()
    st = exu.SimulationSettings()
    n = int(round(duration / dt))
    st.timeIntegration.numberOfSteps = n
    st.timeIntegration.endTime = n * dt
    st.timeIntegration.verboseMode = 0
    st.timeIntegration.generalizedAlpha.spectralRadius = (1 - scene.simulation.alpha) / (1 + scene.simulation.alpha)
    st.solutionSettings.writeSolutionToFile = False
    st.solutionSettings.sensorsWritePeriod = dt
    t0 = time.perf_counter()
    mbs.SolveDynamic(st)
    wall = time.perf_counter() - t0
    pos, rot = mbs.GetSensorStoredData(s_pos), mbs.GetSensorStoredData(s_rot)
    return wall, n, pos[:, 0], pos[:, 3], rot[:, 1:4]


def jaxslosh_barge(scene, duration):
    setup = prepare(scene, duration=duration)
    b, solver = _core(setup.built), setup.solver
    carry, f0 = start(b, solver)
    advance(b, solver, carry, setup.n_steps, 1)             # compile
    t0 = time.perf_counter()
    c2, fr = advance(b, solver, carry, setup.n_steps, 1)
    jax.block_until_ready(fr)
    wall = time.perf_counter() - t0
    rpy = np.asarray(js.run.rpy_from_quat(fr.q))
    return wall, setup.n_steps, np.asarray(fr.t), np.asarray(fr.X0)[:, 2], rpy


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    try:
        import exudyn
    except ImportError:
        print("exudyn is not installed (pip install exudyn): nothing to compare")
        return
    scene = js.load_scene(os.path.join(ROOT, "scenes", "vessel_only.toml"))
    dt = scene.simulation.dt
    ex = min((exudyn_barge(scene, a.duration, dt) for _ in range(a.repeat)), key=lambda r: r[0])
    jx = min((jaxslosh_barge(scene, a.duration) for _ in range(a.repeat)), key=lambda r: r[0])
    print(f"exudyn {exudyn.__version__}, jax {jax.__version__}; {os.cpu_count()} cpu; vessel alone, dt = {dt} s, "
          f"{a.duration} s, best of {a.repeat}")
    print(f"{'code':10} {'steps':>6} {'wall s':>8} {'steps/s':>10} {'us/step':>8}")
    for name, r in (("exudyn", ex), ("jaxslosh", jx)):
        print(f"{name:10} {r[1]:6d} {r[0]:8.4f} {r[1] / r[0]:10.0f} {1e6 * r[0] / r[1]:8.2f}")
    print(f"speed ratio jaxslosh / exudyn: {ex[0] / jx[0]:.2f}")
    # response: exudyn's sensors hold t = 0 and every step; our frames also
    t = jx[2]
    z_ex = np.interp(t, ex[2], ex[3])
    ang_ex = np.stack([np.interp(t, ex[2], ex[4][:, i]) for i in range(2)], axis=1)
    d_ang = np.abs(ang_ex - jx[4][:, :2]).max(axis=0)
    print(f"largest difference over the run: roll {d_ang[0]:.3e} rad, pitch {d_ang[1]:.3e} rad (peaks "
          f"{np.abs(jx[4][:, 0]).max():.3e}, {np.abs(jx[4][:, 1]).max():.3e}), heave {np.abs(z_ex - jx[3]).max():.3e} m "
          f"(exudyn: Tait-Bryan xyz angles and its generalized-alpha; ours: roll-pitch-yaw and HHT)")


if __name__ == "__main__":
    main()
