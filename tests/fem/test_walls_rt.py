"""The face-normal liquid ("rt") in elastic walls (liquid/face/walls.py): the wall faces' fluxes are the
volumes the walls sweep, imposed by elimination.

The references are potential theory, written here. A 2-D tank a long, filled to h, whose end wall
x = a moves as one rigid dof on a spring: a piston (wall velocity profile f(z) = 1, mass m, spring
k) or a flap hinged at the bottom (f(z) = z, inertia I about the hinge, torsion spring k), the liquid
sliding along it. With phi = i omega X psi, the wall's equation is

    k - omega^2 m - rho b omega^2 int_0^h psi(a, z) f(z) dz = 0.

psi is expanded in the vertical modes of frequency omega (Z_0 = cosh(k_0 z), omega^2 = g k_0
tanh(k_0 h), standing in x as cos(k_0 x); Z_m = cos(k_m z), omega^2 = -g k_m tan(k_m h),
evanescent as cosh(k_m x)), orthogonal on [0, h] (one Sturm-Liouville problem):

    int psi f dz = -(f, Z_0)^2 / (N_0 k_0 tan(k_0 a)) + sum_m (f, Z_m)^2 / (N_m k_m tanh(k_m a)),

N_j = int Z_j^2. For the piston a second closed form is checked against it: with
psi = (x^2 - z^2) / (2 a) + sum_n C_n cos(k_n x) cosh(k_n z), k_n = n pi / a,

    int psi dz = a h / 3 + h^3 / (3 a) - g h^2 / (a omega^2)
                 + sum_n 2 a omega^2 tanh(k_n h) / ((n pi)^2 k_n (omega_n^2 - omega^2)),

omega_n^2 = g k_n tanh(k_n h) the rigid tank's modes (the n = 0 term is the mean level's rise: the
hydrostatic stiffness rho g b h^2 / a). The roots of the wall's equation are the coupled modes.
"""
import functools

import numpy as np
import pytest
import scipy.linalg as sl
import scipy.optimize as so
import scipy.sparse as sp

from jaxslosh.liquid.face.element import build_face_liquid, face_modes
from jaxslosh.fem.mesh import box_mesh
from jaxslosh.liquid.walls import build_walls
from jaxslosh.liquid.face.walls import (build_face_tank_with_walls, couple_walls, face_area_weights, face_tank_modes,
                                   wall_faces)
from jaxslosh.scene.types import Fluid, Material, Tank, Walls

RHO, G, C = 1000.0, 9.81, 1500.0
A, B, H = 1.0, 0.2, 0.5


def piston_integral(w, terms=4000):
    n = np.arange(1, terms + 1)
    k = n * np.pi / A
    wn2 = G * k * np.tanh(k * H)
    return A * H / 3 + H ** 3 / (3 * A) - G * H * H / (A * w * w) + \
        np.sum(2 * A * w * w * np.tanh(k * H) / ((n * np.pi) ** 2 * k * (wn2 - w * w)))


def _bisect(f, lo, hi):
    """Roots of increasing functions on brackets (vectorised bisection to round-off)."""
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = f(mid) < 0
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def wall_integral(w, shape, terms=400):
    """int psi(a, z) f(z) dz by the vertical modes, f = 1 ("piston") or z ("flap")."""
    nu = w * w / G
    k0 = _bisect(lambda k: k * np.tanh(k * H) - nu, np.array([1e-12]), np.array([nu + 50.0 / H]))[0]
    m = np.arange(1, terms + 1)
    km = _bisect(lambda y: y * np.tan(y) + nu * H, (m - 0.5) * np.pi + 1e-12, m * np.pi - 1e-12) / H
    if shape == "piston":
        p0, pm = np.sinh(k0 * H) / k0, np.sin(km * H) / km
    else:
        p0 = H * np.sinh(k0 * H) / k0 - (np.cosh(k0 * H) - 1) / k0 ** 2
        pm = H * np.sin(km * H) / km + (np.cos(km * H) - 1) / km ** 2
    N0, Nm = H / 2 + np.sinh(2 * k0 * H) / (4 * k0), H / 2 + np.sin(2 * km * H) / (4 * km)
    return -p0 ** 2 / (N0 * k0 * np.tan(k0 * A)) + np.sum(pm ** 2 / (Nm * km * np.tanh(km * A)))


def wall_roots(shape, m, k, upto, n):
    """The first n coupled frequencies below `upto` rad/s (sign changes of the wall's equation that
    are not its poles at the rigid tank's modes)."""
    f = lambda w: k - w * w * m - RHO * B * w * w * wall_integral(w, shape)      # noqa: E731
    ws = np.linspace(0.3, upto, 800)
    v = np.array([f(w) for w in ws])
    roots = []
    for i in np.flatnonzero(np.sign(v[:-1]) != np.sign(v[1:])):
        r = so.brentq(f, ws[i], ws[i + 1], xtol=1e-13)
        if abs(f(r)) < 1e-6 * max(abs(v[i]), abs(v[i + 1])):          # a root, not a pole
            roots.append(r)
    return np.array(roots[:n])


def wall_tank(shape, nx, nz, m, k):
    """The tank meshed nx x 1 x nz, its x = a wall one dof: every wall face there sweeps
    int_f f(z) dA per unit of it."""
    nodes, elements = box_mesh((A, B, H), (nx, 1, nz))
    model = build_face_liquid(nodes, elements, H, RHO, C, G)
    faces = wall_faces(model)
    on = faces[np.abs(model.nodes[model.faces[faces]][:, :, 0].mean(axis=1) - A) < 1e-9]
    W = face_area_weights(model, on)[:, :, 0]
    profile = np.ones((len(on), 4)) if shape == "piston" else model.nodes[model.faces[on]][:, :, 2]
    Tw = sp.coo_matrix((np.einsum("ka,ka->k", W, profile), (on, np.zeros(len(on), dtype=int))),
                       shape=(len(model.faces), 1))
    return couple_walls(model, Tw, np.array([[m]]), np.array([[k]]))


def test_the_two_piston_references_agree():
    for w in (2.0, 4.5, 6.0, 9.0):
        assert abs(wall_integral(w, "piston") / piston_integral(w) - 1) < 1e-9


@pytest.mark.parametrize("shape, m, k, n", [("piston", 50.0, 2000.0, 4), ("piston", 20.0, 4.0e4, 3),
                                            ("flap", 2.0, 150.0, 4)])
def test_a_moving_wall_against_potential_theory(shape, m, k, n):
    """A soft piston (first coupled mode 4.504 rad/s; the rigid tank's 5.32), a stiffer one (5.294,
    7.826, 9.609) and a flap (4.677, 7.141, 8.679, 9.951), whose flux varies down the wall: the first
    n coupled modes within 0.6 % on 8x1x4 and 0.1 % on 16x1x8, the largest error falling at second
    order (at least 3x per halving; measured 3.3 to 6)."""
    ref = wall_roots(shape, m, k, 14.0, n)
    errs = []
    for nx, nz in ((8, 4), (16, 8)):
        md = face_tank_modes(wall_tank(shape, nx, nz, m, k), n)
        errs.append(np.abs(md.omega[:n] / ref - 1))
        print(nx, nz, md.omega[:n], md.kind[:n])
    print("reference", ref, "errors", errs)
    assert len(ref) == n
    assert errs[0].max() < 6e-3 and errs[1].max() < 1e-3
    assert errs[1].max() < errs[0].max() / 3


def test_a_held_piston_gives_the_rigid_tank():
    """An infinitely stiff piston is a rigid wall: the coupled modes are the rigid tank's, and the
    circulation modes are left out and counted as with rigid walls."""
    tw = wall_tank("piston", 8, 4, 50.0, 1e14)
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
    normal = np.zeros_like(centre)              # the box's outward normals, from the plane each face is on
    for axis, top in ((0, 5.0), (1, 5.0), (2, None)):
        normal[np.abs(centre[:, axis]) < 1e-9, axis] = -1.0
        if top is not None:
            normal[np.abs(centre[:, axis] - top) < 1e-9, axis] = 1.0
    assert np.all(np.abs(normal).sum(axis=1) == 1)
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
    dry = np.sqrt(sl.eigh(w.stiffness[np.ix_(f, f)], np.kron(w.mass, np.eye(3))[np.ix_(f, f)], eigvals_only=True,
                          subset_by_index=[0, 2]))
    print("wet", wet, "dry", dry)
    assert len(wet) == 3 and np.all(wet < 0.95 * dry)
    assert not np.any(np.isclose(md.omega ** 2, tw.kappa, rtol=1e-6))
