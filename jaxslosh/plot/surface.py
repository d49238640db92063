"""The tanks and their deformed free surface in the inertial frame: snapshots (the paper's Figure
5(a)) and an animated GIF."""
from __future__ import annotations

import numpy as np
from matplotlib.animation import FuncAnimation, PillowWriter

from ..fem.outline import outline
from ..fem.shapes import TankGeometry
from ..fem.slip import HEX_FACES
from ..physics.kinematics import rotation_matrix
from ..scene.load import load_scene, tomllib
from ..scene.types import SceneError
from .results import figure


class _Tanks:
    """What drawing the tanks of a result needs, computed once: each tank's origin, size, free-surface
    nodes (those at the fill depth) and their triangulation, and the plot's half-width."""

    def __init__(self, r):
        if not r.tanks:
            raise ValueError("the result holds no liquid fields (run with tanks, without --no-fields)")
        scene = {t["name"]: t for t in tomllib.loads(r.scene_text).get("tanks", [])}
        try:
            shapes = {t.name: t for t in load_scene(r.scene_text).tanks}
        except (SceneError, OSError):       # e.g. a mesh file named relative to a folder left behind
            shapes = {}
        self.r = r
        self.time = np.asarray(r.time)
        self.tanks = []
        for name, tf in r.tanks.items():
            if name not in scene:
                raise ValueError(f"the result's scene has no tank named {name!r}")
            origin = np.asarray(scene[name]["origin"], float)
            depth = float(scene[name]["fill_depth"])
            geo = shapes[name].geometry if name in shapes else TankGeometry(size=tuple(scene[name]["size"]))
            nodes = np.asarray(tf.nodes)
            s, tri = _surface_triangles(nodes, np.asarray(tf.elements), depth)
            lines = [origin + line for line in outline(geo, depth)]
            self.tanks.append((name, origin, nodes[s], s, tri, lines))
        self.span = max(float(np.max(scene[name]["size"])) for name in r.tanks) * 0.75

    def index(self, t) -> int:
        """The saved frame nearest to time t."""
        return int(np.argmin(np.abs(self.time - t)))

    def draw(self, ax, i: int, scale: float) -> None:
        """Frame i on a 3D axes: the tanks' edges turned and moved with the hull, and each deformed
        free surface (displacements magnified by `scale`), in the inertial frame around the COG."""
        r = self.r
        A = np.asarray(rotation_matrix(np.asarray(r.vessel.quaternion[i])))
        X0 = np.asarray(r.vessel.position[i])
        for name, origin, surface, s, tri, lines in self.tanks:
            D = np.asarray(r.tanks[name].displacement[i])[s]
            p = X0 + (origin + surface + scale * D) @ A.T
            ax.plot_trisurf(p[:, 0], p[:, 1], p[:, 2], triangles=tri, cmap="Blues", alpha=0.9, linewidth=0.2,
                            edgecolor="k")
            for line in lines:
                seg = X0 + line @ A.T
                ax.plot(seg[:, 0], seg[:, 1], seg[:, 2], color="0.3", lw=0.8)
        ax.set_title(f"t = {self.time[i]:.2f} s", fontsize=9)
        ax.set_xlim(X0[0] - self.span, X0[0] + self.span)
        ax.set_ylim(X0[1] - self.span, X0[1] + self.span)
        ax.set_zlim(X0[2] - self.span, X0[2] + self.span)
        ax.set_box_aspect((1, 1, 1))
        ax.set_xlabel("X (m)")
        ax.set_ylabel("Y (m)")
        ax.set_zlabel("Z (m)")


def _surface_triangles(nodes, elements, depth):
    """(the free surface's node indices, its triangles over them): each element face whose four nodes
    lie at the fill depth, cut in two (a baffled or U-shaped surface is not bridged, as Delaunay would)."""
    on = np.isclose(nodes[:, 2], depth)
    F = elements[:, HEX_FACES].reshape(-1, 4)
    F = F[on[F].all(axis=1) & (np.array([len(set(f)) for f in F]) == 4)]
    s = np.unique(F)
    local = np.full(nodes.shape[0], -1)
    local[s] = np.arange(s.size)
    tri = np.concatenate([local[F[:, [0, 1, 2]]], local[F[:, [0, 2, 3]]]])
    return s, tri


def _surface_title(scale: float) -> str:
    return "tank and free surface in the inertial frame" + (f" (displacements x{scale:g})" if scale != 1 else "")


def plot_free_surface(r, out: str, times=None, scale: float = 1.0):
    """The counterpart of the paper's Figure 5(a): the hull's attitude and the deformed free surface
    of every tank at a few instants, in the inertial frame (displacements magnified by `scale`).
    Returns the figure written."""
    tanks = _Tanks(r)
    if times is None:
        times = np.linspace(tanks.time[0], tanks.time[-1], 4)
    idx = [tanks.index(tt) for tt in times]
    fig = figure(4.2 * len(idx), 4.2)
    for j, i in enumerate(idx):
        tanks.draw(fig.add_subplot(1, len(idx), j + 1, projection="3d"), i, scale)
    fig.suptitle(_surface_title(scale), fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    return fig


def animate_free_surface(r, out: str, scale: float = 1.0, fps: float = 10.0, every: int | None = None,
                         max_frames: int = 100, dpi: int = 80, progress=None) -> int:
    """An animated GIF of the tanks and their deformed free surface in the inertial frame (the frames
    of `plot_free_surface`, one per shown instant; displacements magnified by `scale`). Every
    `every`-th saved frame is shown (default: the stride that keeps at most `max_frames`), `fps`
    frames per second. `progress(done, total)`, if given, is called as the frames are written
    (done = frames written so far, last with done = total). Returns the number of frames written."""
    tanks = _Tanks(r)
    n = len(tanks.time)
    if every is None:
        every = max(1, -(-n // max(1, int(max_frames))))
    if int(every) < 1:
        raise ValueError(f"every: must be at least 1, got {every}")
    if not fps > 0:
        raise ValueError(f"fps: must be positive, got {fps}")
    idx = list(range(0, n, int(every)))
    fig = figure(5.0, 5.0)
    ax = fig.add_subplot(projection="3d")
    fig.suptitle(_surface_title(scale), fontsize=10)

    def frame(i):
        ax.cla()
        tanks.draw(ax, i, scale)
        return ()

    anim = FuncAnimation(fig, frame, frames=idx, init_func=lambda: (), blit=False, cache_frame_data=False)
    # matplotlib calls back once a frame is drawn, before it is rendered into the file: frames
    # written so far = its index
    report = None if progress is None else (lambda i, _: progress(i, len(idx)))
    anim.save(out, writer=PillowWriter(fps=fps), dpi=dpi, progress_callback=report)
    if progress is not None:
        progress(len(idx), len(idx))
    return len(idx)
