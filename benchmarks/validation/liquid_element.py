"""Convergence of the liquid elements on tank sections with re-entrant geometry (issue 30): the
face-normal element ("rt"), the stabilized one and the paper's, against the project's independent
2-D potential-flow reference (tests/sloshing_reference.py, P2 triangles, converged), on sections
meshed two elements thick (tests/section_meshes.py, or the loader's own box-with-baffle and
prismatic meshes). Prints one table per case: mesh, elements, the first three sloshing
frequencies' errors (%) per element.

    python -m benchmarks.validation.liquid_element [--elements rt,stabilized] [--cases utube,hanging,...] [--quick]
    python -m benchmarks.validation.liquid_element --cases shapes
    python -m benchmarks.validation.liquid_element --cases six
    python -m benchmarks.validation.liquid_element --cases cost [--meshes 10x10x6,20x20x12]
    python -m benchmarks.validation.liquid_element --cases lng [--meshes 24x8,24x16,48x16,48x32]

``lng``: the LNG section (1 m square, 0.2 m chamfers at the bottom and the top) filled 10, 30, 50,
70, 85 and 95 % (one case each: lng10, ..., lng95), on meshes refined across (y) and up (z):
2 x 24 x 8 to 2 x 96 x 64 (``--meshes`` takes the y x z counts).

``six``: the same tanks and the LNG tank at 10 to 95 % (tests/shape_cases.py), the worst of the first
six sloshing modes' errors (%) per element, and the element each tank gets by default (on modes /
at full order).
``cost``: rt's times (s) on a 5x5x3 m box: build, face_modes (10), face_basis (20 modes and the
static correction), face_invariants.
``shapes``: every tank shape on about 1,000 elements (tests/shape_cases.py), 3-D, the first six
sloshing modes' errors (%) against closed forms or the reference's prism modes, per element, and
the non-sloshing modes the nodal elements put among them.

Every case is 2-D (modes uniform across the two-element thickness), so the nodal elements' modes
are taken as the sloshing modes whose free-surface share is > 0.5, and the first three of those
matched with the reference's. The elements' matrices and modes are jaxslosh's fem/ internals (what
is validated here has no public API); the references are the tests' (tests/sloshing_reference.py,
tests/section_meshes.py, tests/shape_cases.py; run from the repository root). `--quick`: the
standing baffle on its coarsest mesh.
"""
import os
import tempfile
import time

import numpy as np

from jaxslosh.liquid.nodal.model import build_liquid
from jaxslosh.liquid.face.element import build_face_liquid, face_modes
from jaxslosh.liquid.modes import liquid_modes
from jaxslosh.geometry import Baffle, Box, MeshFile, Prismatic
from benchmarks.harness import Table, parser
from tests.section_meshes import hopper_baffle_hex, u_tube_hex
from tests.sloshing_reference import (Baffle as RefBaffle, prismatic, rectangle, rectilinear_sloshing_omegas,
                                      section_sloshing_omegas, u_tube)

G, RHO, C = 9.81, 1000.0, 1500.0
T = 0.2          # the sections' thickness (x), two elements


def reference(case):
    if case == "utube":
        return rectilinear_sloshing_omegas(u_tube(8.0, 1.0, 0.3, 2.0), 1.0, G, n=3, h_target=0.025)
    if case == "hanging":
        return section_sloshing_omegas(rectangle(1.0, 1.0), 0.5, G, 3, [RefBaffle(0.5, 0.8, hanging=True)], 0.005)
    if case == "standing":
        return section_sloshing_omegas(rectangle(1.0, 1.0), 0.5, G, 3, [RefBaffle(0.5, 0.3)], 0.005)
    if case == "hopper":
        return section_sloshing_omegas(prismatic(1.0, 1.0, 0.2, 0.2), 0.5, G, 3, [RefBaffle(0.5, 0.3)], 0.005)
    if case.startswith("lng"):
        h = 0.005 if case == "lng30" else 0.01
        return section_sloshing_omegas(prismatic(1.0, 1.0, 0.2, 0.2, 0.2, 0.2), _fill(case), G, 3, (), h)
    raise ValueError(case)


LNG_FILLS = ("lng10", "lng30", "lng50", "lng70", "lng85", "lng95")
LNG_MESHES = "24x8,24x16,48x16,48x32,96x32,48x64,96x64"


def _fill(case):
    return int(case[3:]) / 100.0


def meshes(case, lng_meshes=LNG_MESHES):
    """[(label, geometry, depth, counts)]: a shape the loader would build (a mesh file for
    the sections it cannot describe)."""
    out = []
    if case == "utube":
        for ny, nz in [(40, 10), (80, 20), (160, 40)]:
            out.append((f"2x{ny}x{nz}", _file(*u_tube_hex(8.0, 1.0, 0.3, 1.0, ny, nz, T)), 1.0, None))
    elif case in ("hanging", "standing"):
        bf = Baffle("y", 0.5, "top", 0.8) if case == "hanging" else Baffle("y", 0.5, "bottom", 0.3)
        for ny, nz in [(20, 10), (40, 20), (80, 40)]:
            out.append((f"2x{ny}x{nz}", Box(size=(T, 1.0, 1.0), baffles=(bf,)), 0.5, (2, ny, nz)))
    elif case == "hopper":
        for ny, nz in [(20, 10), (40, 20), (80, 40)]:
            out.append((f"2x{ny}x{nz}", _file(*hopper_baffle_hex(1.0, 0.2, 0.5, 0.5, 0.3, ny, nz, T)), 0.5, None))
    elif case.startswith("lng"):
        geo = Prismatic(size=(T, 1.0, 1.0), chamfers=((0.2, 0.2), (0.2, 0.2)))
        for ny, nz in [tuple(int(v) for v in m.split("x")) for m in lng_meshes.split(",")]:
            out.append((f"2x{ny}x{nz}", geo, _fill(case), (2, ny, nz)))
    return out


_TMP = tempfile.mkdtemp(prefix="jaxslosh-bench-")


def _file(nodes, elements):
    import meshio
    path = os.path.join(_TMP, f"m{len(os.listdir(_TMP))}.vtu")
    meshio.write(path, meshio.Mesh(nodes, [("hexahedron", elements)]))
    return MeshFile(size=tuple(np.ptp(nodes, axis=0)), file=path)


def omegas(element, geo, depth, counts, n=3):
    if element == "rt":
        tm = geo.mesh(depth, counts or (1, 1, 1))
        m = build_face_liquid(tm.nodes, tm.elements, tm.depth, RHO, C, G)
        md = face_modes(m, n)
        return md.omega[:n], len(tm.elements)
    model = build_liquid(geo.size, depth, counts or (1, 1, 1), RHO, C, G, element=element, sparse=True, geometry=geo)
    md = liquid_modes(model, n=4 * n + 6)
    w = md.omega[np.array(md.kind) == "sloshing"]
    return w[:n], len(model.elements)


def shapes(elements, markdown=False):
    from tests import shape_cases
    table = Table(("tank", "{}"), ("elements", "{:d}"), *((f"{e}, modes 1-6 (%)", "{}") for e in elements))
    for name in shape_cases.CASES:
        geo, depth, mesh, _, ref_w = shape_cases.case(name)
        cells = []
        for element in elements:
            w, ne, kinds = shape_cases.sloshing_omegas(geo, depth, mesh, element)
            other = sum(k != "sloshing" for k in kinds)
            cells.append(", ".join(f"{e:+.2f}" for e in (w / ref_w[:len(w)] - 1) * 100)
                         + (f" ({other} other modes among them)" if other else ""))
        table.add(name, ne, *cells)
    table.print(markdown)


def six(elements, names, markdown=False):
    """Per shape, the worst of the first six sloshing modes' errors (%) and which mode, per element,
    and the element a scene gets when it leaves `element` out, on modes and at full order."""
    from tests import shape_cases
    from jaxslosh.scene.shape import default_element
    table = Table(("tank", "{}"), ("elements", "{:d}"), ("default on modes / full order", "{}"),
                  *((f"{e}: worst of modes 1-6 (%)", "{}") for e in elements))
    for name in names:
        geo, depth, mesh, _, ref_w = shape_cases.case(name)
        cells = []
        for element in elements:
            w, ne, kinds = shape_cases.sloshing_omegas(geo, depth, mesh, element)
            err = (w / ref_w[:len(w)] - 1) * 100
            worst = int(np.argmax(np.abs(err)))
            other = sum(kind != "sloshing" for kind in kinds)
            cells.append(f"{err[worst]:+.2f} (mode {worst + 1})" + ("" if len(w) == 6 else " (missing)")
                         + (f", {other} other modes among them" if other else ""))
        counts = mesh or (1, 1, ne)
        default = "/".join(default_element(geo, depth, counts, reduced)[0] for reduced in (True, False))
        table.add(name, ne, default, *cells)
    table.print(markdown)


def cost(meshes, markdown=False):
    from jaxslosh.liquid.face.element import face_basis, face_invariants
    table = Table(("mesh", "{}"), ("face unknowns", "{:,}"), ("build", "{:.1f}"), ("face_modes (10)", "{:.1f}"),
                  ("face_basis (20 + correction)", "{:.1f}"), ("invariants", "{:.1f}"))
    for mesh in meshes:
        counts = tuple(int(v) for v in mesh.split("x"))
        t = [time.perf_counter()]
        tm = Box(size=(5.0, 5.0, 4.0)).mesh(3.0, counts)
        m = build_face_liquid(tm.nodes, tm.elements, 3.0, RHO, C, G)
        t.append(time.perf_counter())
        face_modes(m, 10)
        t.append(time.perf_counter())
        V = face_basis(m, (0.0, 0.0, 0.0), 20)[0]
        t.append(time.perf_counter())
        face_invariants(m, V, (0.0, 0.0, 0.0))
        t.append(time.perf_counter())
        dt = np.diff(t)
        table.add(mesh, int(m.free.sum()), *dt)
    table.print(markdown)


def main():
    p = parser(__doc__)
    p.add_argument("--elements", default="rt,stabilized")
    p.add_argument("--cases", default="utube,hanging,standing,hopper,lng30")
    p.add_argument("--meshes", default=None, help="cost: 10x10x6,20x20x12,30x30x16; lng: " + LNG_MESHES)
    a = p.parse_args()
    if a.cases == "cost":
        return cost((a.meshes or "10x10x6,20x20x12,30x30x16").split(","), a.markdown)
    if a.cases == "shapes":
        return shapes(a.elements.split(","), a.markdown)
    if a.cases == "six":
        from tests import shape_cases
        return six(a.elements.split(","), shape_cases.CASES[:3] + shape_cases.LNG_FILLS + shape_cases.CASES[3:],
                   a.markdown)
    if a.quick:
        a.cases = "standing"
    cases = [c for name in a.cases.split(",") for c in (LNG_FILLS if name == "lng" else (name,))]
    for case in cases:
        ref = reference(case)
        print(f"\n{case}: reference omega = {', '.join(f'{w:.5f}' for w in ref)} rad/s")
        table = Table(("mesh", "{}"), ("elements", "{:d}"),
                      *((f"{e} err % (modes 1, 2, 3)", "{}") for e in a.elements.split(",")))
        for label, geo, depth, counts in meshes(case, a.meshes or LNG_MESHES)[:1 if a.quick else None]:
            cells = []
            for element in a.elements.split(","):
                w, ne = omegas(element, geo, depth, counts)
                err = (w / ref[:len(w)] - 1) * 100
                cells.append(", ".join(f"{e:+.2f}" for e in err) + ("" if len(w) == 3 else " (missing)"))
            table.add(label, ne, *cells)
        table.print(a.markdown)


if __name__ == "__main__":
    main()
