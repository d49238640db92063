"""The outline of a tank of any shape, to draw (plot/surface.py)."""
from __future__ import annotations

import numpy as np

from .shapes import TankGeometry, read_mesh
from .slip import boundary


def outline(geo: TankGeometry, fill_depth: float, mesh=None):
    """The tank's outline to draw: polylines (k, 3) in tank-local coordinates (the box's 12 edges, a
    prismatic section at both ends and its corner lines, a cylinder's end circles and four lines
    along it, a mesh's feature edges, each baffle's plate). `mesh` = (nodes, elements) of a mesh
    tank's liquid (a result keeps them), else its file is read."""
    a, b, H = geo.size
    lines = []
    if geo.kind == "prismatic" or geo.plain_box or geo.kind == "box":
        (cw, ch), (tw, th) = geo.chamfers if geo.kind == "prismatic" else ((0, 0), (0, 0))
        sec = [(cw, 0), (b - cw, 0), (b, ch), (b, H - th), (b - tw, H), (tw, H), (0, H - th), (0, ch)]
        sec = [p for i, p in enumerate(sec) if i == 0 or np.hypot(*np.subtract(p, sec[i - 1])) > 1e-12]
        sec = np.array(sec + [sec[0]], dtype=float)
        for x in (0.0, a):
            lines.append(np.column_stack([np.full(len(sec), x), sec]))
        lines += [np.array([[0.0, y, z], [a, y, z]]) for y, z in sec[:-1]]
    elif geo.kind == "cylinder":
        t = np.linspace(0, 2 * np.pi, 73)
        if geo.axis == "z":
            ring = np.column_stack([a / 2 * (1 + np.cos(t)), b / 2 * (1 + np.sin(t))])
            lines += [np.column_stack([ring, np.full(len(t), z)]) for z in (0.0, H)]
            lines += [np.array([[x, y, 0.0], [x, y, H]]) for x, y in ring[:-1:18]]
        else:
            L, B = (a, b) if geo.axis == "x" else (b, a)
            ring = np.column_stack([B / 2 * (1 + np.cos(t)), H / 2 * (1 + np.sin(t))])
            for u in (0.0, L):
                pts = np.column_stack([np.full(len(t), u), ring])
                lines.append(pts if geo.axis == "x" else pts[:, [1, 0, 2]])
            for s_, z in ring[:-1:18]:
                seg = np.array([[0.0, s_, z], [L, s_, z]])
                lines.append(seg if geo.axis == "x" else seg[:, [1, 0, 2]])
    elif geo.kind == "mesh":
        nodes, elements = (np.asarray(mesh[0], float), np.asarray(mesh[1])) if mesh is not None else read_mesh(geo.file)
        bd = boundary(nodes, elements, float(nodes[:, 2].max()))
        faces = np.concatenate([bd.wall_faces, bd.top_faces])
        X = nodes[faces]
        nrm = np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        edges = np.concatenate([np.sort(faces[:, [i, (i + 1) % 4]], axis=1) for i in range(4)])
        owner = np.tile(np.arange(len(faces)), 4)
        _, inv = np.unique(edges, axis=0, return_inverse=True)
        inv = inv.reshape(-1)
        order = np.argsort(inv, kind="stable")
        for k in range(0, len(order) - 1):
            i, j = order[k], order[k + 1]
            if inv[i] == inv[j] and nrm[owner[i]] @ nrm[owner[j]] < np.cos(np.radians(30.0)):
                lines.append(nodes[edges[i]])
    for bf in geo.baffles:
        z0, z1 = (0.0, bf.height) if bf.mount == "bottom" else (H - bf.height, H)
        if bf.normal == "x":
            lines.append(np.array([[bf.at, 0, z0], [bf.at, b, z0], [bf.at, b, z1], [bf.at, 0, z1], [bf.at, 0, z0]]))
        else:
            lines.append(np.array([[0, bf.at, z0], [a, bf.at, z0], [a, bf.at, z1], [0, bf.at, z1], [0, bf.at, z0]]))
    return [np.asarray(line, dtype=float) for line in lines]

