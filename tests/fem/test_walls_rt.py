"""The face-normal liquid ("rt") in elastic walls (fem/walls_rt.py): the wall faces' fluxes are the
volumes the walls sweep, imposed by elimination.

The reference is potential theory, written here: a 2-D tank a long, filled to h, whose end wall
x = a is a rigid piston of mass m_p on a spring k_p (one dof X, the liquid sliding along it). With
psi = (x^2 - z^2) / (2 a) + sum_n C_n cos(k_n x) cosh(k_n z), k_n = n pi / a (psi_x = 1 on the
piston, 0 on the other wall and the bottom), the free-surface condition gives C_n, and the piston's
equation k_p - omega^2 m_p - rho b omega^2 int_0^h psi(a, z) dz = 0, with

    int psi dz = a h / 3 + h^3 / (3 a) - g h^2 / (a omega^2)
                 + sum_n 2 a omega^2 tanh(k_n h) / ((n pi)^2 k_n (omega_n^2 - omega^2)),

omega_n^2 = g k_n tanh(k_n h) the rigid tank's sloshing modes (the n = 0 term is the mean level's
rise: the hydrostatic stiffness rho g b h^2 / a of the piston). Its roots are the coupled modes.
"""
import functools

import numpy as np
import pytest
import scipy.optimize as so
import scipy.sparse as sp

from jaxslosh.fem.liquid_rt import build_face_liquid, face_modes
from jaxslosh.fem.mesh import box_mesh
from jaxslosh.fem.walls_rt import (build_face_tank_with_walls, couple_walls, face_area_weights, face_tank_modes,
                                   wall_faces)
from jaxslosh.fem.walls import build_walls
from jaxslosh.scene.types import Fluid, Material, Tank, Walls

RHO, G, C = 1000.0, 9.81, 1500.0
A, B, H = 1.0, 0.2, 0.5


def piston_integral(w, terms=4000):
    n = np.arange(1, terms + 1)
    k = n * np.pi / A
    wn2 = G * k * np.tanh(k * H)
    return A * H / 3 + H ** 3 / (3 * A) - G * H * H / (A * w * w) + \
        np.sum(2 * A * w * w * np.tanh(k * H) / ((n * np.pi) ** 2 * k * (wn2 - w * w)))


def piston_roots(mp, kp, upto, n):
    """The first n coupled frequencies of the piston tank below `upto` rad/s (sign changes of the
    characteristic function that are not its poles at the rigid tank's modes)."""
    f = lambda w: kp - w * w * mp - RHO * B * w * w * piston_integral(w)      # noqa: E731
    ws = np.linspace(0.3, upto, 6000)
    v = np.array([f(w) for w in ws])
    roots = []
    for i in np.flatnonzero(np.sign(v[:-1]) != np.sign(v[1:])):
        r = so.brentq(f, ws[i], ws[i + 1], xtol=1e-13)
        if abs(f(r)) < 1e-6 * max(abs(v[i]), abs(v[i + 1])):          # a root, not a pole
            roots.append(r)
    return np.array(roots[:n])


def piston_tank(nx, nz, mp, kp):
    nodes, elements = box_mesh((A, B, H), (nx, 1, nz))
    m = build_face_liquid(nodes, elements, H, RHO, C, G)
    faces = wall_faces(m)
    on = np.abs(m.nodes[m.faces[faces]][:, :, 0].mean(axis=1) - A) < 1e-9
    col = face_area_weights(m, faces[on]).sum(axis=1)[:, 0]          # the piston moves along x, as one
    Tw = sp.coo_matrix((col, (faces[on], np.zeros(on.sum(), dtype=int))), shape=(len(m.faces), 1))
    return couple_walls(m, Tw, np.array([[mp]]), np.array([[kp]]))


@pytest.mark.parametrize("mp, kp, n", [(50.0, 2000.0, 4), (20.0, 4.0e4, 3)])
def test_piston_wall_against_potential_theory(mp, kp, n):
    """A soft piston (the first coupled mode 4.504 rad/s, the rigid tank's 5.32) and a stiffer one
    (5.294, 7.826, 9.609 rad/s): the first n coupled modes within 0.4 % on 8x1x4 and
    0.05 % on 16x1x8, the largest error falling at second order (at least 3x per halving)."""
    ref = piston_roots(mp, kp, 14.0, n)
    errs = []
    for nx, nz in ((8, 4), (16, 8)):
        md = face_tank_modes(piston_tank(nx, nz, mp, kp), n)
        errs.append(np.abs(md.omega[:n] / ref - 1))
        print(nx, nz, md.omega[:n], md.kind[:n])
    print("reference", ref, "errors", errs)
    assert len(ref) == n
    assert errs[0].max() < 4e-3 and errs[1].max() < 5e-4
    assert errs[1].max() < errs[0].max() / 3


def test_a_held_piston_gives_the_rigid_tank():
    """An infinitely stiff piston is a rigid wall: the coupled modes are the rigid tank's, and the
    circulation modes are left out and counted as with rigid walls."""
    tw = piston_tank(8, 4, 50.0, 1e14)
    md = face_tank_modes(tw, 4)
    rigid = face_modes(tw.model, 4)
    np.testing.assert_allclose(md.omega, rigid.omega, rtol=1e-8)
    assert md.circulation == rigid.circulation > 0


SIZE, FILL, MESH = (5.0, 5.0, 4.0), 3.0, (3, 3, 2)


def _tank(young, thickness=0.1):
    return Tank("tank", (0.0, 0.0, 0.0), SIZE, FILL, MESH, "elastic", Fluid(),
                Walls(thickness, Material(young, 0.3, 7850.0)))


@functools.lru_cache(maxsize=None)
def _model():
    nodes, elements = box_mesh((5.0, 5.0, FILL), MESH)
    return build_face_liquid(nodes, elements, FILL, RHO, C, G)


def test_wall_faces_sweep_the_walls_volume():
    """The map from the shell's nodal displacements to the wall faces' fluxes: a uniform wall
    displacement v sweeps A_f n_f . v through each face (n_f outward), and the walls bulging out by a
    field w along their normals sweep the volume int w dA (a quadratic field, integrated exactly)."""
    tw = build_face_tank_with_walls(_tank(2.1e11), _model())
    w = tw.walls
    nq = tw.nq
    Tw = tw.T[:, nq:]
    faces = wall_faces(tw.model)
    X = tw.model.nodes[tw.model.faces[faces]]
    centre = X.mean(axis=1)
    normal = np.where(np.abs(centre[:, :1]) < 1e-9, [-1, 0, 0], 0) + np.where(np.abs(centre[:, :1] - 5) < 1e-9,
                                                                               [1, 0, 0], 0)
    normal = normal + np.where(np.abs(centre[:, 1:2]) < 1e-9, [0, -1, 0], 0) + \
        np.where(np.abs(centre[:, 1:2] - 5) < 1e-9, [0, 1, 0], 0) + np.where(np.abs(centre[:, 2:]) < 1e-9, [0, 0, -1], 0)
    area = np.abs(np.linalg.norm(np.cross(X[:, 1] - X[:, 0], X[:, 3] - X[:, 0]), axis=1))
    v = np.array([0.3, -0.2, 0.7])
    u = np.tile(v, len(w.nodes))[tw.wall_dofs]
    np.testing.assert_allclose((Tw @ u)[faces], area * (normal @ v), rtol=1e-12, atol=1e-14)
    # the x = 5 wall bulging out by w = y z (bilinear on each face): its faces sweep int y z dA
    u = np.zeros((len(w.nodes), 3))
    u[:, 0] = w.nodes[:, 1] * w.nodes[:, 2]
    q = (Tw @ u.reshape(-1)[tw.wall_dofs])[faces]
    on = np.abs(centre[:, 0] - 5) < 1e-9
    lo, hi = X[on].min(axis=1), X[on].max(axis=1)
    exact = 0.25 * (hi[:, 1] ** 2 - lo[:, 1] ** 2) * (hi[:, 2] ** 2 - lo[:, 2] ** 2)
    np.testing.assert_allclose(q[on], exact, rtol=1e-12)


def test_sloshing_tends_to_the_rigid_tank_as_the_walls_stiffen():
    """The first five sloshing modes in 10 cm walls of E = 2e9 ... 2.1e13 Pa: only softer than the
    rigid tank's, and the difference falls monotonically to below 1e-4."""
    rigid = face_modes(_model(), 5).omega
    errs = []
    for E in (2e9, 2.1e10, 2.1e11, 2.1e13):
        md = face_tank_modes(build_face_tank_with_walls(_tank(E), _model()), n=8)
        slosh = md.omega[[k == "sloshing" for k in md.kind]][:5]
        errs.append(np.max(np.abs(slosh / rigid - 1)))
        assert np.all(slosh <= rigid * (1 + 1e-9))
    print("max errors of the first five:", errs)
    assert all(a > b for a, b in zip(errs, errs[1:])) and errs[-1] < 1e-4


def test_a_flexible_wall_vibrates_lower_wet_than_dry():
    """The walls' modes with the liquid lie below the same walls' dry modes (the liquid's added
    mass), and the circulation modes, at omega^2 = kappa, are none of those listed."""
    E = 2.1e11
    tw = build_face_tank_with_walls(_tank(E), _model())
    md = face_tank_modes(tw, n=60)
    wet = md.omega[[k == "wall" for k in md.kind]][:3]
    w = build_walls(SIZE, FILL, MESH, 0.1, E, 0.3, 7850.0)
    f = np.flatnonzero(~np.repeat(w.held, 3))
    import scipy.linalg as sl
    dry = np.sqrt(sl.eigh(w.stiffness[np.ix_(f, f)], np.kron(w.mass, np.eye(3))[np.ix_(f, f)], eigvals_only=True,
                          subset_by_index=[0, 2]))
    print("wet", wet, "dry", dry)
    assert len(wet) == 3 and np.all(wet < 0.95 * dry)
    assert not np.any(np.isclose(md.omega ** 2, tw.kappa, rtol=1e-6))
