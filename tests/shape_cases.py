"""Every tank shape on a mesh of about 1,000 elements, with its independent reference (issue 30's
"every shape: the first 6 sloshing modes within 2.5 %"): closed forms for the box and the vertical
cylinder, tests/sloshing_reference.py's prism modes (a section's modes times cos(m pi x / L), every
m) for the prismatic tanks, the horizontal cylinders, the U-tube and the baffled tanks. Shared by
tests/fem/test_liquid_element_shapes.py and benchmarks/validation/liquid_element.py (``--cases shapes``).

Each case: (geometry, fill depth, mesh counts or None for a mesh file, the element to use,
reference omega (6,) in rad/s)."""
from __future__ import annotations

import os
import tempfile

import numpy as np

try:
    import sloshing_reference as ref
    from section_meshes import u_tube_hex
except ImportError:     # imported as tests.shape_cases from the repository root (benchmarks/validation/)
    from tests import sloshing_reference as ref
    from tests.section_meshes import u_tube_hex

G = 9.81
N = 6

#: the element each shape is checked with: "rt" wherever the stabilized one misses 2.5 % on these
#: meshes (benchmarks/validation/liquid_element.py --cases shapes prints both)
ELEMENT = {"box": "stabilized", "low_hopper": "stabilized"}


def _vertical_cylinder(R, h, n):
    out = []
    for e, m, _ in ref.cylinder_bessel_roots(n):
        k = e / R
        out += [float(np.sqrt(G * k * np.tanh(k * h)))] * (1 if m == 0 else 2)
    return np.array(out[:n])


def _u_tube_file(nx, ny, nz, length):
    import meshio
    nodes, elements = u_tube_hex(8.0, 1.0, 0.3, 1.0, ny, nz, length, nx)
    path = os.path.join(tempfile.mkdtemp(prefix="jaxslosh-utube-"), "u_tube.vtu")
    meshio.write(path, meshio.Mesh(nodes, [("hexahedron", elements)]))
    return path, tuple(float(v) for v in np.ptp(nodes, axis=0))


def case(name):
    """(geometry, depth, mesh or None, element, reference omega (N,)) of the named case."""
    from jaxslosh.liquid.modes import analytic_sloshing_omegas
    from jaxslosh.geometry import Baffle, Box, Cylinder, MeshFile, Prismatic

    lng = ref.prismatic(6.0, 4.0, 1.5, 1.0, 1.5, 1.0)
    lng_geo = Prismatic(size=(8.0, 6.0, 4.0), chamfers=((1.5, 1.0), (1.5, 1.0)))
    hcyl = Cylinder(size=(3.0, 2.0, 2.0), axis="x")
    el = ELEMENT.get(name, "rt")
    if name == "box":
        return (Box(size=(5.0, 5.0, 4.0)), 3.0, (10, 10, 10), el,
                analytic_sloshing_omegas(5.0, 5.0, 3.0, G, N))
    if name.startswith("lng_"):
        d = 4.0 * int(name[4:]) / 100
        # filled 10 % (0.4 m), the modes barely vary with depth: the elements go along the surface
        # (on 10 x 12 x 8 the sixth mode, three half waves along the 8 m, is 3.3 % high)
        mesh = (12, 16, 5) if name == "lng_10" else (10, 12, 8)
        return lng_geo, d, mesh, el, ref.prism_sloshing_omegas(lng, d, 8.0, G, N, h_target=0.08)[0]
    if name == "low_hopper":
        return (Prismatic(size=(6.0, 8.0, 1.5), chamfers=((1.0, 0.3), (0.0, 0.0))), 1.2,
                (8, 16, 8), el, ref.prism_sloshing_omegas(ref.prismatic(8.0, 1.5, 1.0, 0.3), 1.2, 6.0, G, N,
                                                          h_target=0.05)[0])
    if name == "v_trough":
        return (Prismatic(size=(2.0, 2.0, 1.0), chamfers=((1.0, 1.0), (0.0, 0.0))), 0.8,
                (8, 12, 10), el, ref.prism_sloshing_omegas(ref.prismatic(2.0, 1.0, 1.0, 1.0), 0.8, 2.0, G, N,
                                                           h_target=0.04)[0])
    if name == "vertical_cylinder":
        return (Cylinder(size=(2.0, 2.0, 2.0), axis="z"), 1.0, (10, 10, 10), el,
                _vertical_cylinder(1.0, 1.0, N))
    if name.startswith("horizontal_cylinder_"):
        d = {"25": 0.5, "50": 1.0, "80": 1.6}[name.rsplit("_", 1)[1]]
        return hcyl, d, (10, 16, 6), el, ref.prism_sloshing_omegas(ref.circle(1.0), d, 3.0, G, N, h_target=0.04)[0]
    if name == "u_tube_file":
        path, size = _u_tube_file(5, 40, 10, 1.0)
        return (MeshFile(size=size, file=path), 1.0, None, el,
                ref.prism_sloshing_omegas(ref.u_tube(8.0, 1.0, 0.3, 2.0), 1.0, 1.0, G, N, h_target=0.05)[0])
    if name in ("hanging_baffle", "standing_baffle"):
        hanging = name == "hanging_baffle"
        bf = Baffle("y", 0.5, "top", 0.8) if hanging else Baffle("y", 0.5, "bottom", 0.3)
        rbf = ref.Baffle(0.5, 0.8, hanging=True) if hanging else ref.Baffle(0.5, 0.3)
        return (Box(size=(1.0, 1.0, 1.0), baffles=(bf,)), 0.5, (6, 18, 9), el,
                ref.prism_sloshing_omegas(ref.rectangle(1.0, 1.0), 0.5, 1.0, G, N, h_target=0.02, baffles=[rbf])[0])
    raise ValueError(name)


CASES = ("box", "lng_30", "lng_90", "low_hopper", "v_trough", "vertical_cylinder", "horizontal_cylinder_25",
         "horizontal_cylinder_50", "horizontal_cylinder_80", "u_tube_file", "hanging_baffle", "standing_baffle")
#: the LNG tank at the other fills (10 to 95 %: within the hopper, above it, into the top chamfers)
LNG_FILLS = ("lng_10", "lng_50", "lng_70", "lng_85", "lng_95")


def sloshing_omegas(geo, depth, mesh, element, n=N):
    """(omega of the n lowest sloshing modes, elements, kinds of the modes up to the n-th sloshing
    one) of the tank with the given element."""
    if element == "rt":
        from jaxslosh.liquid.face.element import build_face_liquid, face_modes
        tm = geo.mesh(depth, mesh or (1, 1, 1))
        md = face_modes(build_face_liquid(tm.nodes, tm.elements, tm.depth, 1000.0, 1500.0, G), n)
        return md.omega, len(tm.elements), list(md.kind)
    from jaxslosh.liquid.nodal.model import build_liquid
    from jaxslosh.liquid.modes import liquid_modes
    model = build_liquid(geo.size, depth, mesh or (1, 1, 1), 1000.0, 1500.0, G, element=element, sparse=True,
                         geometry=geo)
    md = liquid_modes(model, n=3 * n + 2)
    kind = np.array(md.kind)
    k = np.flatnonzero(kind == "sloshing")
    upto = k[n - 1] + 1 if len(k) >= n else len(kind)
    return md.omega[k[:n]], len(model.elements), list(kind[:upto])
