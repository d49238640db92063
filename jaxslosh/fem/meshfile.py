"""A tank's liquid read from a mesh file (meshio), and checked before anything is built on it.

The liquid element needs hexahedra with a positive Jacobian everywhere; a bad element in a file does
not fail loudly downstream, it moves the modes (a hexahedron with two coincident corners moved a
tank's second mode by 10 %). So a file is refused, with the first element or node at fault, when:

* it cannot be read, or holds no 8-node hexahedra (or mixes them with other solids);
* an element has two corners at one place (a collapsed hexahedron);
* an element is a zero-thickness layer: two of its opposite faces closer than `THIN` times the
  mesh's typical edge (0.3 and 0.30000000000000004 written as two node planes);
* two nodes lie a hair apart (closer than `THIN` times the typical edge, but not at exactly the
  same place): two node planes meant as one, which would cut the liquid by a wall. Nodes at exactly
  one place stay apart on purpose: the two faces of a thin plate;
* an element's Jacobian is zero or of both signs at its corners (twisted, concave, tangled);
* a face is shared by more than two elements (non-manifold), or two elements lie on the same side
  of the face they share (they overlap).

An element whose Jacobian is negative at every corner is a left-handed (inverted) numbering of a
good hexahedron: it is re-oriented, and the count is kept (`jaxslosh check` reports it).

Indices in the messages are the file's: node n is the n-th point (0-based), element e the e-th
hexahedron in the file's order (0-based). NumPy only.
"""
from __future__ import annotations

import contextlib
import functools
import io
import os
from typing import NamedTuple

import numpy as np

#: opposite faces closer than this share of the mesh's median edge make a zero-thickness layer
THIN = 1e-6
#: a corner whose scaled Jacobian (the triple product of its three unit edges) is at most this is degenerate
FLAT_CORNER = 1e-9
#: for each corner of the hex8 element, its three neighbours along +xi, +eta, +zeta (right-handed order)
_CORNER_EDGES = np.array([[1, 3, 4], [2, 0, 5], [3, 1, 6], [0, 2, 7],
                          [7, 5, 0], [4, 6, 1], [5, 7, 2], [6, 4, 3]])
#: the six faces, each counter-clockwise seen from outside the element
_FACES = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]])
#: the four edges along each parametric direction
_EDGES = np.array([[[0, 1], [3, 2], [4, 5], [7, 6]], [[0, 3], [1, 2], [4, 7], [5, 6]],
                   [[0, 4], [1, 5], [2, 6], [3, 7]]])
#: a left-handed element's corners renumbered right-handed (1 and 3, 5 and 7 swapped: a mirror image)
_FLIP = [0, 3, 2, 1, 4, 7, 6, 5]


class HexMesh(NamedTuple):
    nodes: np.ndarray        # (N, 3) the used points, in the file's order
    elements: np.ndarray     # (E, 8) hex8, right-handed
    reoriented: int          # elements the file gave left-handed, re-oriented here


def read_mesh_file(path) -> HexMesh:
    """The checked hexahedral mesh of a file; ValueError with one line naming what is wrong. Read
    once per file version (the loader, the volume, the build and `check` all ask): shared arrays."""
    try:
        st = os.stat(path)
    except OSError as e:
        raise ValueError(f"cannot read the mesh file {os.fspath(path)!r}: {e.strerror}") from None
    return _read(str(path), st.st_mtime_ns, st.st_size)


@functools.lru_cache(maxsize=8)
def _read(path, mtime_ns, size) -> HexMesh:
    try:
        import meshio
    except ImportError as e:   # a core dependency (pyproject.toml); an install that skipped it gets one line
        raise ValueError("reading a tank mesh needs meshio: pip install meshio") from e
    said = io.StringIO()
    try:
        # meshio prints each format's failure and calls sys.exit(1) when none reads the file
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            m = meshio.read(path)
    except (Exception, SystemExit) as e:
        why = " ".join(s.strip() for s in (said.getvalue().splitlines() + [str(e) if not isinstance(e, SystemExit)
                                                                          else ""]) if s.strip())
        why = why.replace("Error: ", "")
        raise ValueError(f"cannot read the mesh file {path!r}: {why or type(e).__name__}") from None
    hexes = [c.data for c in m.cells if c.type == "hexahedron"]
    other = sorted({c.type for c in m.cells if c.type in ("tetra", "wedge", "pyramid", "hexahedron20",
                                                          "hexahedron27", "tetra10")})
    if not hexes:
        raise ValueError(f"the mesh file {path!r} holds no 8-node hexahedra" + (f" (it has {other})" if other else ""))
    if other:
        raise ValueError(f"the mesh file {path!r} mixes hexahedra with {other}: give 8-node hexahedra only")
    elements = np.concatenate(hexes).astype(int)
    points = np.asarray(m.points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"the mesh file {path!r} is not three-dimensional (its points have "
                         f"{points.shape[1] if points.ndim == 2 else 0} coordinates)")
    if elements.min() < 0 or elements.max() >= len(points):
        e = int(np.flatnonzero((elements < 0).any(1) | (elements >= len(points)).any(1))[0])
        raise ValueError(f"the mesh file {path!r}: element {e} names a node that the file does not have")
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if bad.size and np.isin(bad, elements).any():
        n = int(bad[np.isin(bad, elements)][0])
        raise ValueError(f"the mesh file {path!r}: node {n} has a coordinate that is not a number: {_xyz(points[n])}")
    elements, flipped = check_hexahedra(points, elements, path)
    used = np.unique(elements)
    remap = np.full(len(points), -1)
    remap[used] = np.arange(used.size)
    return HexMesh(points[used], remap[elements], flipped)


def check_hexahedra(points, elements, name="mesh"):
    """(elements right-handed, how many were re-oriented), or ValueError naming the first element
    or face at fault (module docstring); `points`, `elements` as in the file."""
    X = points[elements]                                         # (E, 8, 3)
    edges = np.linalg.norm(X[:, _EDGES[..., 1]] - X[:, _EDGES[..., 0]], axis=-1)    # (E, 3, 4)
    h = float(np.median(edges))
    if not h > 0:
        raise ValueError(f"the mesh file {name!r}: its elements have no extent (median edge 0)")
    # zero-thickness layer: the distance between opposite faces along a direction, by its longest edge
    thick = edges.max(axis=2)                                    # (E, 3)
    thin = thick <= THIN * h
    if thin.any():
        e = int(np.flatnonzero(thin.any(axis=1))[0])
        k = int(np.argmax(thin[e]))
        a, b = elements[e, _EDGES[k, 0]]
        raise ValueError(f"the mesh file {name!r}: element {e} is a zero-thickness layer: its faces through node "
                         f"{a} at {_xyz(points[a])} and node {b} at {_xyz(points[b])} are {thick[e, k]:.3g} m apart "
                         f"(the mesh's elements are about {h:.3g} m): merge the two node planes")
    # coincident corners: any two of an element's eight corners within THIN * h (the same node too)
    iu = np.triu_indices(8, 1)
    close = np.linalg.norm(X[:, iu[0]] - X[:, iu[1]], axis=-1) <= THIN * h
    if close.any():
        e = int(np.flatnonzero(close.any(axis=1))[0])
        k = int(np.flatnonzero(close[e])[0])
        a, b = elements[e, iu[0][k]], elements[e, iu[1][k]]
        which = f"node {a} twice" if a == b else f"nodes {a} and {b}"
        raise ValueError(f"the mesh file {name!r}: element {e} is collapsed: two of its corners coincide "
                         f"({which} at {_xyz(points[a])})")
    # corner Jacobians, scaled by the three edges' lengths: +1 for a right angle, 0 for a flat corner
    va = X[:, _CORNER_EDGES[:, 0]] - X
    vb = X[:, _CORNER_EDGES[:, 1]] - X
    vc = X[:, _CORNER_EDGES[:, 2]] - X
    J = np.einsum("eci,eci->ec", np.cross(va, vb), vc)
    scaled = J / (np.linalg.norm(va, axis=2) * np.linalg.norm(vb, axis=2) * np.linalg.norm(vc, axis=2))
    left = (scaled < -FLAT_CORNER).all(axis=1)
    ok = (scaled > FLAT_CORNER).all(axis=1) | left
    if not ok.all():
        e = int(np.flatnonzero(~ok)[0])
        s = scaled[e] if (scaled[e] > 0).sum() >= 4 else -scaled[e]
        c = int(np.argmin(s))
        n = elements[e, c]
        what = "zero" if abs(s[c]) <= FLAT_CORNER else "negative"
        raise ValueError(f"the mesh file {name!r}: element {e} has a {what} Jacobian at its corner node {n} at "
                         f"{_xyz(points[n])} (scaled {s[c]:.3g}): a flat, concave or twisted hexahedron")
    elements = elements.copy()
    elements[left] = elements[left][:, _FLIP]
    _check_faces(points, elements, name)
    _check_near_nodes(points, np.unique(elements), THIN * h, name)
    return elements, int(left.sum())


def _check_near_nodes(points, used, tol, name):
    """Two nodes of different elements a hair apart (0 < distance <= tol) are two node planes where
    the mesher meant one (0.3 and 0.30000000000000004): the liquid would be cut there by a wall.
    Nodes at exactly the same place are kept apart on purpose (a thin plate's two faces)."""
    from scipy.spatial import cKDTree
    P = points[used]
    pairs = cKDTree(P).query_pairs(tol, output_type="ndarray")
    if not len(pairs):
        return
    d = np.linalg.norm(P[pairs[:, 0]] - P[pairs[:, 1]], axis=1)
    near = pairs[d > 0]
    if len(near):
        a, b = sorted(used[near[np.argmin(near.min(axis=1))]])
        raise ValueError(f"the mesh file {name!r}: nodes {a} at {_xyz(points[a])} and {b} at {_xyz(points[b])} are "
                         f"{np.linalg.norm(points[a] - points[b]):.3g} m apart: two node planes where one is meant "
                         f"(a zero-thickness layer cutting the liquid); merge them")


def _check_faces(points, elements, name):
    """A face belongs to at most two elements, and two elements that share one lie on its two sides."""
    E = len(elements)
    faces = elements[:, _FACES].reshape(-1, 4)                   # (6E, 4), outward counter-clockwise
    key = np.sort(faces, axis=1)
    _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    owner = np.repeat(np.arange(E), 6)
    if count.max() > 2:
        f = int(np.flatnonzero(count[inv] > 2)[0])
        who = owner[inv == inv[f]]
        nodes = faces[f]
        raise ValueError(f"the mesh file {name!r}: the face of nodes {', '.join(str(n) for n in nodes)} (one at "
                         f"{_xyz(points[nodes[0]])}) is shared by {len(who)} elements ({', '.join(str(w) for w in who)}): "
                         f"a face may join two elements at most (non-manifold mesh)")
    shared = np.flatnonzero(count[inv] == 2)
    if shared.size:
        order = np.argsort(inv[shared], kind="stable")
        pairs = shared[order].reshape(-1, 2)                     # the two sides of each shared face
        f0, f1 = faces[pairs[:, 0]], faces[pairs[:, 1]]
        # the same face seen from its two sides runs the other way round: f1 is f0 reversed, rotated
        start = np.argmax(f1 == f0[:, :1], axis=1)
        rev = np.take_along_axis(f1, (start[:, None] - np.arange(4)[None, :]) % 4, axis=1)
        same = ~(rev == f0).all(axis=1)
        if same.any():
            p = int(np.flatnonzero(same)[0])
            a, b = owner[pairs[p]]
            n = faces[pairs[p, 0], 0]
            raise ValueError(f"the mesh file {name!r}: elements {a} and {b} overlap: they lie on the same side of the "
                             f"face they share (node {n} at {_xyz(points[n])} is one of its corners)")


def _xyz(p) -> str:
    return "[" + ", ".join(repr(float(x)) for x in p) + "]"
