"""Side by side with Exudyn (C++ floating-frame multibody code): same scene, same step, one run.

    pip install exudyn          # a benchmark-only dependency, not one of jaxslosh's
    python -m benchmarks.validation.exudyn_compare [--duration 20] [--repeat 3] [--modes 8 20]
        [--only all|vessel|ffrf-reduced|ffrf] [--full-duration 0.5] [--nodal] [--quick]

1. The vessel alone (scenes/vessel_only.toml) on hydrostatic springs: in Exudyn a rigid body (Euler
parameters) tied to the ground by CreateRigidBodySpringDamper with the heave, roll and pitch
stiffnesses rho g A_w, rho g V GM_T, rho g V GM_L and useIntrinsicFormulation=False (its default
intrinsic formulation gives wrong hydrostatics); Exudyn's generalized-alpha with the spectral radius
of our HHT alpha = 0.01, (1 - alpha) / (1 + alpha). Prints steps per second of both and the largest
difference of roll, pitch and heave over the run.

2. The paper example (scenes/paper_ship_tank.toml: rigid ship + 5x5x5 liquid hexahedra in a rigid
tank, omega0 = (0.1, 0.05, 0), HHT alpha = 0.01, dt = 0.01 s), the liquid as ONE Exudyn floating-
frame body built from OUR matrices (`exudyn_paper`):
  * mesh: our liquid's 216 nodes (vessel frame, origin at the ship's COG) plus six point masses at
    +-a e_x, +-b e_y, +-c e_z that carry the ship's mass and principal inertia exactly; they do not
    deform (zero rows of the mode basis; held coordinates of the nodal body), so the reference node
    of the body is the ship itself (no joint, no second body on the node);
  * mass kron(Ms, I3) (our consistent liquid mass); stiffness our K on the free dofs (acoustic, free
    surface i.e. the hydrostatic pre-stress, the rotation penalty on curl d, the surface
    stabilisation), zero on the wall-normal dofs;
  * slip walls: the wall-normal dofs are single nodal coordinates in the body frame. The reduced body
    (ObjectFFRFreducedOrder, `--only ffrf-reduced`) gets OUR mode basis: the natural modes of the
    liquid with the walls held (jaxslosh.reduction, mass-normalised, zero on those dofs; 8 modes
    become 9 because the degenerate (1,0)/(0,1) pair is not split). The full-order body
    (`--only ffrf`) is the same object with ALL 468 modes, a complete basis of the free dofs, so the
    same model as the nodal one. ObjectFFRF on the nodal coordinates (`--nodal`): the held
    coordinates each by one CoordinateConstraint to ground (a MarkerNodeCoordinate per held
    coordinate). Held instead by one CoordinateVectorConstraint on a MarkerObjectODE2Coordinates of
    the whole body (as Exudyn's own Tisserand constraint is written), the run did not get through
    one step: Exudyn differentiates the constraint forces C_q^T lambda numerically, column by
    column, and each column rebuilt that constraint's dense (held x 7 + 3n) Jacobian (gdb: the
    time was in CObjectConnectorCoordinateVector::ComputeJacobianAE under
    NumericalConstraintJacobianDerivative, already for the initial accelerations; no step within
    10 minutes, Exudyn 1.13.6). With the scalar constraints Newton converges in 2-3 iterations a
    step (modified Newton, EigenSparse; EXUdense is 2x slower, full Newton 40x slower) and the
    nodal body gives the modal all-modes body's response to round-off;
  * gravity: the liquid's weight at its current centre of mass (a LoadForceVector of m g on a
    MarkerSuperElementPosition over all liquid nodes weighted by nodal mass, which is exactly m_i g on
    every node, deformation included) less the same weight at the undeformed centre of mass fixed in
    the frame. Net: the weight of the displacement field d -- the load M g_body on d with g turning
    with the body, and the moment (sum m_i d_i) x g on the hull -- which is what our "balanced" model
    has (GM_T and GM_L are with the liquid frozen; the static buoyancy balances the weight). NOT
    Exudyn's LoadMassProportional: on ObjectFFRFreducedOrder its moment uses the undeformed centre of
    mass only (checked: the rotational generalized force does not change with the modal
    coordinates), which drops the free-surface moment;
  * start: our discrete hydrostatic equilibrium (the free-dof displacement of jaxslosh's start, or
    its modal coordinates), the same initial angular velocity;
  * buoyancy: the vessel-only springs above.
Not representable in a floating-frame body with a constant stiffness: our rotation penalty acts on
the ABSOLUTE rotation of the liquid, curl d + 2 theta with theta the body's rotation since t = 0
(docs/theory.md item 5: an inviscid liquid does not spin up with the tank). Exudyn's body can only hold
its d-d block (the penalty on curl d: the liquid is pushed to turn with the tank). So Exudyn is
compared with our runs with that coupling dropped ("relative penalty", `relative_penalty()`), which
mean the same model, and with our real runs, which shows the size of the effect. The reduced bodies
get pure natural modes and are compared with our reduced run on the same basis ([tanks.reduction]
static_correction = false, relative penalty: then the basis is exactly those modes); our real
modal-reduction run ([tanks.reduction] modes = 8 or 20, static correction) is listed as well.
Remaining differences between "the same model" runs: the springs' Tait-Bryan form against our
conservative restoring potential, and Exudyn's generalized-alpha against our HHT (as in 1.).
Timings: ours best of --repeat after compilation (benchmarks/harness.py: js.Stepper's steps, no
frames kept; the trajectories are js.simulate's), Exudyn's SolveDynamic once (modified Newton, as
Exudyn's FFRF examples; it gives the same answer with fewer Jacobians), sensors every step in both.
"""
import contextlib
import dataclasses
import os
import time

import jax
import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

import jaxslosh as js
from benchmarks.harness import ROOT, parser, time_scene


def _settings(exu, scene, duration, dt):
    """Exudyn's settings for our run: n steps of dt, generalized-alpha with the spectral radius of
    our HHT alpha, (1 - alpha) / (1 + alpha); sensors stored in memory, no files."""
    st = exu.SimulationSettings()
    n = int(round(duration / dt))
    st.timeIntegration.numberOfSteps = n
    st.timeIntegration.endTime = n * dt
    st.timeIntegration.verboseMode = 0
    st.timeIntegration.generalizedAlpha.spectralRadius = (1 - scene.simulation.alpha) / (1 + scene.simulation.alpha)
    st.solution.file.write = False
    st.solution.sensors.writePeriod = dt
    return st, n


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
                                     storeInternal=True, writeToFile=False))
    s_rot = mbs.AddSensor(SensorBody(bodyNumber=body, outputVariableType=exu.OutputVariableType.Rotation,
                                     storeInternal=True, writeToFile=False))
    mbs.Assemble()
    st, n = _settings(exu, scene, duration, dt)
    t0 = time.perf_counter()
    mbs.SolveDynamic(st)
    wall = time.perf_counter() - t0
    pos, rot = mbs.GetSensorStoredData(s_pos), mbs.GetSensorStoredData(s_rot)
    return wall, n, pos[:, 0], pos[:, 3], rot[:, 1:4]


def jaxslosh_barge(scene, duration):
    """Our run: the step's wall time (benchmarks/harness.py, best of 1 after compilation) and the
    trajectory of `js.simulate` (t = 0 included)."""
    sc = js.scene_with(scene, {"simulation.duration": duration})
    n = int(round(duration / sc.simulation.dt))
    rec = time_scene("vessel alone", sc, n, repeat=1)
    r = js.simulate(sc)
    return rec.run_s, n, np.asarray(r.time), np.asarray(r.vessel.position)[:, 2], np.asarray(r.vessel.roll_pitch_yaw)


def vessel_compare(a):
    import exudyn
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


# ----------------------------------------------------------------------------------------------
# the paper's example: the liquid as an Exudyn floating-frame body built from our matrices

PAPER = os.path.join(ROOT, "scenes", "paper_ship_tank.toml")


@contextlib.contextmanager
def relative_penalty():
    """Our liquid with its rotation penalty on the RELATIVE rotation (curl d) only: the coupling to
    the body rotation theta (Liquid.Kdt, Ktt; docs/theory.md item 5) dropped. This is what a floating-
    frame body with a constant stiffness matrix can hold, so it is the model Exudyn is given."""
    import jaxslosh.liquid.nodal.model as lq
    import jaxslosh.liquid.modal.reduction as rd
    orig = lq.build_liquid

    def patched(*args, **kw):
        return dataclasses.replace(orig(*args, **kw), rotation_coupling=None, rotation_stiffness=None)

    lq.build_liquid = patched
    rd._cached_basis.cache_clear()          # its key does not say whether the coupling is there
    try:
        yield
    finally:
        lq.build_liquid = orig
        rd._cached_basis.cache_clear()


def paper_text(modes=None, static_correction=True) -> js.Scene:
    """The paper example, its tank reduced to `modes` where given (the name kept from the TOML days)."""
    sc = js.load_scene(PAPER)
    if modes is None:
        return sc
    return js.scene_with(sc, {"tanks[0].reduction.modes": modes,
                              "tanks[0].reduction.static_correction": static_correction})


def jaxslosh_paper(sc, duration, repeat, relative=False):
    """Our run of a paper-example variant: the step's wall time (benchmarks/harness.py, best of
    `repeat` after compilation), roll-pitch-yaw, heave and the vertical displacement of probe B
    (`js.simulate`), t = 0 included; `built`: the model (js.Stepper's)."""
    sc = js.scene_with(sc, {"simulation.duration": duration})
    n = int(round(duration / sc.simulation.dt))
    with relative_penalty() if relative else contextlib.nullcontext():
        stepper = js.Stepper(sc)
        rec = time_scene("paper", sc, n, repeat)
        r = js.simulate(sc)
    zb = np.asarray(r.probes["B"].position)[:, 2]
    return dict(wall=rec.run_s, n=n, unknowns=rec.unknowns, built=stepper.built, t=np.asarray(r.time),
                rpy=np.asarray(r.vessel.roll_pitch_yaw), z=np.asarray(r.vessel.position)[:, 2], pb=zb - zb[0])


def ship_point_masses(mass, inertia):
    """Six equal point masses at +-a e_x, +-b e_y, +-c e_z with the ship's mass and principal
    moments of inertia about its COG (the frame origin)."""
    Ixx, Iyy, Izz = np.diag(np.asarray(inertia, dtype=float)) if np.ndim(inertia) == 2 else inertia
    k = 1.5 / mass
    a, b, c = np.sqrt([k * (Iyy + Izz - Ixx), k * (Ixx + Izz - Iyy), k * (Ixx + Iyy - Izz)])
    return np.array([[a, 0, 0], [-a, 0, 0], [0, b, 0], [0, -b, 0], [0, 0, c], [0, 0, -c]]), np.full(6, mass / 6)


def exudyn_paper(scene, L, kind, basis, q0, duration, dt, probe_w, probe_p):
    """The paper example in Exudyn: one floating-frame body (reference node = the ship's COG, Euler
    parameters) whose mesh is our liquid's nodes plus six point masses carrying the ship's mass
    and inertia; our mass matrix kron(Ms, I3) and our stiffness (acoustic + free surface + rotation
    penalty + surface stabilisation) on the free dofs, zero rows on the wall-normal dofs.

    kind "reduced": ObjectFFRFreducedOrder on `basis` (3N x m, zero on the wall-normal dofs and the
    ship's points), q0 its modal coordinates at t = 0. kind "ffrf": ObjectFFRF on every nodal
    coordinate, the wall-normal ones and the ship's points held by a CoordinateVectorConstraint;
    q0 the nodal displacement (3N,).
    Gravity: the liquid's weight at its current centre of mass (a LoadForceVector on a
    MarkerSuperElementPosition over all liquid nodes, weighted by nodal mass: exactly sum_i m_i g
    on every node), less the same weight at its undeformed centre of mass fixed in the frame (GM_T
    and GM_L are with the liquid frozen and the static buoyancy balances the weight, as in ours).
    Buoyancy: the vessel-only springs (Tait-Bryan form, useIntrinsicFormulation=False)."""
    import exudyn as exu
    import exudyn.itemInterface as eii
    from exudyn.FEM import FEMinterface, ObjectFFRFreducedOrderInterface
    from exudyn.rigidBodyUtilities import AngularVelocity2EulerParameters_t
    from exudyn.utilities import SensorNode
    v, h, env = scene.vessel, scene.vessel.hydrostatics, scene.environment
    g, rho_g = env.gravity, env.water_density * env.gravity
    r, Ms = np.asarray(L.r), np.asarray(L.Ms)
    N = r.shape[0]
    pts, pm = ship_point_masses(v.mass, v.inertia)
    nodes = np.concatenate([r, pts])
    n3 = 3 * nodes.shape[0]
    M3 = sp.kron(sp.block_diag([sp.csr_matrix(Ms), sp.diags(pm)]), sp.eye(3)).tocsr()
    free = np.asarray(L.free)
    Kc = sp.coo_matrix(0.5 * (np.asarray(L.K) + np.asarray(L.K).T))
    K3 = sp.csr_matrix((Kc.data, (free[Kc.row], free[Kc.col])), shape=(n3, n3))
    m_nodes = Ms.sum(axis=1)
    m_l = m_nodes.sum()
    r_c = m_nodes @ r / m_l
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    omega0 = list(v.initial.angular_velocity)
    if kind == "reduced":
        Psi = np.zeros((n3, basis.shape[1]))
        Psi[:3 * N] = basis
        fem = FEMinterface()
        fem.nodes = {"Position": nodes}
        fem.massMatrix, fem.stiffnessMatrix = M3, K3
        fem.modeBasis, fem.eigenValues = {"matrix": Psi, "type": "NormalModes"}, np.ones(Psi.shape[1])
        cms = ObjectFFRFreducedOrderInterface(fem)
        made = cms.AddObjectFFRFreducedOrder(mbs, positionRef=[0, 0, 0], initialVelocity=list(v.initial.velocity),
                                             initialAngularVelocity=omega0)
        body, nRef, nFlex = made["oFFRFreducedOrder"], made["nRigidBody"], made["nGenericODE2"]
        mbs.SetNodeParameter(nFlex, "initialCoordinates", list(np.asarray(q0, dtype=float)))
        flex_sensors = [nFlex]
    else:
        ep0 = [1.0, 0.0, 0.0, 0.0]
        nRef = mbs.AddNode(eii.NodeRigidBodyEP(referenceCoordinates=[0, 0, 0] + ep0, initialVelocities=list(
            v.initial.velocity) + list(AngularVelocity2EulerParameters_t(omega0, ep0))))
        u0 = np.zeros(n3)
        u0[:3 * N] = q0
        nlist = [mbs.AddNode(eii.NodePoint(referenceCoordinates=list(p), initialCoordinates=list(u0[3 * i:3 * i + 3]),
                                           visualization=eii.VNodePoint(show=False))) for i, p in enumerate(nodes)]
        Kmc, Mmc = exu.MatrixContainer(), exu.MatrixContainer()
        Kmc.SetWithSparseMatrix(K3, useDenseMatrix=False)
        Mmc.SetWithSparseMatrix(M3, useDenseMatrix=False)
        body = mbs.AddObject(eii.ObjectFFRF(nodeNumbers=[nRef] + nlist, massMatrixFF=Mmc, stiffnessMatrixFF=Kmc,
                                            visualization=eii.VObjectFFRF(show=False)))
        # the held coordinates (wall normals, ship points): one CoordinateConstraint to ground each.
        # NOT one CoordinateVectorConstraint on a MarkerObjectODE2Coordinates of the body: its
        # Jacobian is a dense (held x 7+3n) matrix that Exudyn differentiates numerically, column by
        # column, for the derivative of C_q^T lambda (initial accelerations and every Jacobian
        # update); here that did not finish one step in 10 minutes
        nG = mbs.AddNode(eii.NodePointGround(referenceCoordinates=[0, 0, 0], visualization=eii.VNodePointGround(show=False)))
        mG = mbs.AddMarker(eii.MarkerNodeCoordinate(nodeNumber=nG, coordinate=0))
        for j in np.setdiff1d(np.arange(n3), free):
            mj = mbs.AddMarker(eii.MarkerNodeCoordinate(nodeNumber=nlist[j // 3], coordinate=int(j % 3)))
            mbs.AddObject(eii.CoordinateConstraint(markerNumbers=[mG, mj], visualization=eii.VCoordinateConstraint(show=False)))
        flex_sensors = [nlist[i] for i in np.flatnonzero(probe_w)]
    mCom = mbs.AddMarker(eii.MarkerSuperElementPosition(bodyNumber=body, meshNodeNumbers=list(range(N)),
                                                        weightingFactors=list(m_nodes / m_l)))
    mbs.AddLoad(eii.LoadForceVector(markerNumber=mCom, loadVector=[0, 0, -m_l * g]))
    a, b, c = pts[0, 0], pts[2, 1], pts[4, 2]         # r_c as an affine combination of the ship's six points
    w = np.array([1 / 6 + r_c[0] / (2 * a), 1 / 6 - r_c[0] / (2 * a), 1 / 6 + r_c[1] / (2 * b),
                  1 / 6 - r_c[1] / (2 * b), 1 / 6 + r_c[2] / (2 * c), 1 / 6 - r_c[2] / (2 * c)])
    mRc = mbs.AddMarker(eii.MarkerSuperElementPosition(bodyNumber=body, meshNodeNumbers=list(range(N, N + 6)),
                                                       weightingFactors=list(w)))
    mbs.AddLoad(eii.LoadForceVector(markerNumber=mRc, loadVector=[0, 0, m_l * g]))
    k = np.diag([0.0, 0.0, rho_g * h.waterplane_area, rho_g * h.displaced_volume * h.gm_t,
                 rho_g * h.displaced_volume * h.gm_l, 0.0])
    ground = mbs.CreateGround(referencePosition=[0, 0, 0])
    mbs.CreateRigidBodySpringDamper(itemNumbers=[ground, nRef], stiffness=k, damping=np.zeros((6, 6)),
                                    useIntrinsicFormulation=False)
    OV = exu.OutputVariableType
    s_pos = mbs.AddSensor(SensorNode(nodeNumber=nRef, outputVariableType=OV.Position, storeInternal=True, writeToFile=False))
    s_rot = mbs.AddSensor(SensorNode(nodeNumber=nRef, outputVariableType=OV.RotationMatrix, storeInternal=True, writeToFile=False))
    s_flex = [mbs.AddSensor(SensorNode(nodeNumber=n, outputVariableType=OV.Coordinates, storeInternal=True, writeToFile=False))
              for n in flex_sensors]
    mbs.Assemble()
    st, n = _settings(exu, scene, duration, dt)
    st.timeIntegration.newton.useModifiedNewton = True     # as Exudyn's FFRF examples; same answer, fewer Jacobians
    if kind == "ffrf":
        st.linearSolverType = exu.LinearSolverType.EigenSparse
    t0 = time.perf_counter()
    try:
        mbs.SolveDynamic(st)
        failed = None
    except Exception as e:      # noqa: BLE001 -- Exudyn raises its SolverError on a failed step
        failed = str(e)
    wall = time.perf_counter() - t0
    if failed:
        return dict(failed=failed, wall=wall, n=n)
    pos = mbs.GetSensorStoredData(s_pos)
    R = mbs.GetSensorStoredData(s_rot)[:, 1:].reshape(-1, 3, 3)
    flex = [mbs.GetSensorStoredData(s)[:, 1:] for s in s_flex]
    if kind == "reduced":
        D = np.einsum("tk,ik->ti", flex[0], basis).reshape(len(pos), N, 3)
        local = probe_p[None, :] + np.einsum("n,tnc->tc", probe_w, D)
    else:
        local = probe_p[None, :] + sum(probe_w[i] * f for i, f in zip(np.flatnonzero(probe_w), flex))
    X = pos[:, 1:4] + np.einsum("tij,tj->ti", R, local)
    roll = np.arctan2(R[:, 2, 1], R[:, 2, 2])             # our roll-pitch-yaw (Z-Y-X) of the same matrix
    pitch = -np.arcsin(np.clip(R[:, 2, 0], -1.0, 1.0))
    yaw = np.arctan2(R[:, 1, 0], R[:, 0, 0])
    unknowns = 7 + (basis.shape[1] if kind == "reduced" else n3)
    return dict(failed=None, wall=wall, n=n, unknowns=unknowns, t=pos[:, 0], rpy=np.stack([roll, pitch, yaw], 1),
                z=pos[:, 3], pb=X[:, 2] - X[0, 2])


def differences(a, b):
    """Largest |a - b| of roll, pitch, heave and probe B over b's times that both runs cover (a interpolated)."""
    keep = b["t"] <= a["t"][-1] + 1e-9
    b = {k: b[k][keep] for k in ("t", "rpy", "z", "pb")}
    t = b["t"]
    f = lambda x: np.interp(t, a["t"], x)  # noqa: E731
    return [np.abs(f(a["rpy"][:, 0]) - b["rpy"][:, 0]).max(), np.abs(f(a["rpy"][:, 1]) - b["rpy"][:, 1]).max(),
            np.abs(f(a["z"]) - b["z"]).max(), np.abs(f(a["pb"]) - b["pb"]).max()]


def paper_compare(a, which):
    import exudyn
    scene = js.load_scene(PAPER)
    dt = scene.simulation.dt
    runs, ex = {}, {}
    print(f"\nexudyn {exudyn.__version__}; paper example (scenes/paper_ship_tank.toml), dt = {dt} s, {a.duration} s; "
          f"ours best of {a.repeat}")
    runs["ours full"] = jaxslosh_paper(paper_text(), a.duration, a.repeat)
    runs["ours full, relative penalty"] = jaxslosh_paper(paper_text(), a.duration, a.repeat, relative=True)
    base = runs["ours full, relative penalty"]["built"]
    L = base.system.liquid
    pw = np.asarray(base.probes.weights)[base.probes.names.index("B")]
    pp = np.asarray(base.probes.points)[base.probes.names.index("B")]
    if which in ("all", "ffrf-reduced"):
        for m in a.modes:
            runs[f"ours {m} modes + static corr."] = jaxslosh_paper(paper_text(m), a.duration, a.repeat)
            r = runs[f"ours {m} modes, relative"] = jaxslosh_paper(paper_text(m, False), a.duration, a.repeat,
                                                                   relative=True)
            Lr = r["built"].system.liquid
            basis = np.asarray(Lr.U).reshape(Lr.U.shape[0], -1).T          # (3N, m): our modes, mass-normalised
            ex[f"exudyn CMS {basis.shape[1]} modes"] = (exudyn_paper(
                scene, L, "reduced", basis, np.asarray(r["built"].c0.d), a.duration, dt, pw, pp),
                f"ours {m} modes, relative")
    if which in ("all", "ffrf"):
        # full order: every natural mode of the liquid with the walls held (a complete basis of the
        # free dofs, so the same model as the nodal one), in Exudyn's modal floating-frame body
        free = np.asarray(L.free)
        M = np.kron(np.asarray(L.Ms), np.eye(3))[np.ix_(free, free)]
        K = 0.5 * (np.asarray(L.K) + np.asarray(L.K).T)
        X = sl.eigh(K, M)[1]
        basis = np.zeros((3 * L.r.shape[0], X.shape[1]))
        basis[free] = X
        ex[f"exudyn CMS all {X.shape[1]} modes"] = (exudyn_paper(
            scene, L, "reduced", basis, X.T @ (M @ np.asarray(base.c0.d)), a.full_duration, dt, pw, pp),
            "ours full, relative penalty")
        if a.nodal:
            d0 = np.zeros(3 * L.r.shape[0])
            d0[free] = np.asarray(base.c0.d)
            ex["exudyn ObjectFFRF (nodal)"] = (exudyn_paper(scene, L, "ffrf", None, d0, a.full_duration, dt, pw, pp),
                                              "ours full, relative penalty")
    print(f"{'model':38} {'unknowns':>8} {'steps':>6} {'wall s':>8} {'steps/s':>9} {'us/step':>10}")
    for name, r in list(runs.items()) + [(k, v[0]) for k, v in ex.items()]:
        if r.get("failed"):
            print(f"{name:38} failed after {r['wall']:.1f} s: {r['failed']}")
            continue
        print(f"{name:38} {r['unknowns']:8d} {r['n']:6d} {r['wall']:8.3f} {r['n'] / r['wall']:9.0f} "
              f"{1e6 * r['wall'] / r['n']:10.1f}")
    f = runs["ours full"]
    print(f"largest difference over the run (peaks of ours full: roll {np.abs(f['rpy'][:, 0]).max():.3e} rad, pitch "
          f"{np.abs(f['rpy'][:, 1]).max():.3e} rad, heave {np.abs(f['z']).max():.3e} m, probe B "
          f"{np.abs(f['pb']).max():.3e} m)")
    print(f"{'':38} {'against':30} {'roll rad':>9} {'pitch rad':>9} {'heave m':>9} {'probe B m':>9}  (over the "
          f"shorter run's time)")

    def row(name, r, ref):
        d = differences(r, runs[ref])
        print(f"{name:38} {ref:30} " + " ".join(f"{x:9.2e}" for x in d))

    for name, (r, same) in ex.items():
        if r.get("failed"):
            continue
        refs = [same, "ours full, relative penalty", "ours full"]
        if "modes," in same:
            refs.append(same.replace(", relative", " + static corr."))
        for ref in dict.fromkeys(refs):
            row(name, r, ref)
    nodal = ex.get("exudyn ObjectFFRF (nodal)", ({"failed": True},))[0]
    cms = [k for k in ex if k.startswith("exudyn CMS all")]
    if not nodal.get("failed") and cms and not ex[cms[0]][0].get("failed"):
        d = differences(nodal, ex[cms[0]][0])         # the same model in Exudyn, nodal against modal
        print("exudyn ObjectFFRF (nodal)              " + f"{cms[0]:30} " + " ".join(f"{x:9.2e}" for x in d))
    row("ours full, relative penalty", runs["ours full, relative penalty"], "ours full")
    for m in a.modes if which in ("all", "ffrf-reduced") else ():
        row(f"ours {m} modes + static corr.", runs[f"ours {m} modes + static corr."], "ours full")
        row(f"ours {m} modes, relative", runs[f"ours {m} modes, relative"], "ours full, relative penalty")


def main():
    ap = parser(__doc__)
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--only", choices=("all", "vessel", "ffrf-reduced", "ffrf"), default="all")
    ap.add_argument("--modes", type=int, nargs="+", default=[8, 20], help="natural modes of the reduced bodies")
    ap.add_argument("--full-duration", type=float, default=0.5,
                    help="simulated time of Exudyn's full-order bodies (s; about 1 s of wall time per step here)")
    ap.add_argument("--nodal", action="store_true",
                    help="also ObjectFFRF on the nodal coordinates (the held ones by scalar CoordinateConstraints, see the docstring)")
    a = ap.parse_args()
    if a.quick:             # 0.5 s, one timing, 8 modes; the vessel alone unless --only says otherwise
        a.duration, a.repeat, a.modes = 0.5, 1, [8]
        a.only = "vessel" if a.only == "all" else a.only
    try:
        import exudyn  # noqa: F401
    except ImportError:
        print("exudyn is not installed (pip install exudyn): nothing to compare")
        return
    if a.only in ("all", "vessel"):
        vessel_compare(a)
    if a.only != "vessel":
        paper_compare(a, a.only)


if __name__ == "__main__":
    main()
