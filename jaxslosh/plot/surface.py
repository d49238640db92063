"""The tanks and their deformed free surface in the inertial frame: snapshots (the paper's Figure
5(a)) and an animated GIF."""
from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.animation import FuncAnimation, PillowWriter
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from ..fem.slip import HEX_FACES
from ..geometry import SHAPES
from ..physics.kinematics import rotation_matrix
from ..scene.load import load_scene, tomllib
from ..scene.types import SceneError
from ..run.guard import finishing
from .results import figure


#: the colour scale of the surface's elevation spans at least this share of the largest tank
#: dimension either side of rest: a surface that stays flat (round-off only) is drawn in one colour
ELEVATION_FLOOR = 1e-4
#: the colour map of the elevation: troughs blue, crests red, rest white; an odd number of colours
#: puts rest in the middle of one (with an even number, round-off either side of 0 flips between two)
ELEVATION_CMAP = colormaps["RdBu_r"].resampled(255)


class _Tanks:
    """What drawing the tanks of a result needs, computed once: each tank's origin, size, free-surface
    nodes (those at the fill depth) and their triangulation, the plot's half-width and the colour
    scale of the surface's elevation (symmetric about rest, one for the whole record)."""

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
        high = 0.0
        for name, tf in r.tanks.items():
            if name not in scene:
                raise ValueError(f"the result's scene has no tank named {name!r}")
            t = scene[name]
            origin = np.asarray(t["origin"], float)
            nodes = np.asarray(tf.nodes)
            elements = np.asarray(tf.elements)
            if name in shapes:
                depth, geo = float(shapes[name].fill_depth), shapes[name].geometry
            else:
                # a mesh tank gives no fill_depth: its free surface is its mesh's top (docs/guide/tank-meshes.md)
                depth = float(t["fill_depth"]) if "fill_depth" in t else float(nodes[:, 2].max())
                geo = SHAPES.get(t.get("shape", "box"), SHAPES["box"]).sketch(t)
            s, tri = _surface_triangles(nodes, elements, depth)
            # a mesh tank's outline from the liquid mesh the result keeps (its file may be elsewhere now)
            lines = [origin + line for line in geo.outline(depth, (nodes, elements))]
            self.tanks.append((name, origin, nodes[s], s, tri, lines))
            if s.size:
                high = max(high, float(np.nanmax(np.abs(np.asarray(tf.displacement)[:, s, 2]), initial=0.0)))
        size = max(float(np.max(scene[name]["size"])) for name in r.tanks)
        self.span = size * 0.75
        self.elevation = Normalize(-max(high, ELEVATION_FLOOR * size), max(high, ELEVATION_FLOOR * size))

    def index(self, t) -> int:
        """The saved frame nearest to time t."""
        return int(np.argmin(np.abs(self.time - t)))

    def colour_bar(self, fig, scale: float):
        """The colour bar of the elevation, in its own axes at the figure's right edge."""
        cax = fig.add_axes((0.92, 0.18, 0.015, 0.64))
        label = "free-surface elevation (m)" + (", true (not magnified)" if scale != 1 else "")
        fig.colorbar(ScalarMappable(norm=self.elevation, cmap=ELEVATION_CMAP), cax=cax, label=label)
        return cax

    def draw(self, ax, i: int, scale: float) -> None:
        """Frame i on a 3D axes: the tanks' edges turned and moved with the hull, and each deformed
        free surface (displacements magnified by `scale`), in the inertial frame around the COG,
        coloured by its elevation above rest (the tank frame's vertical displacement, in metres)."""
        r = self.r
        A = np.asarray(rotation_matrix(np.asarray(r.vessel.quaternion[i])))
        X0 = np.asarray(r.vessel.position[i])
        for name, origin, surface, s, tri, lines in self.tanks:
            D = np.asarray(r.tanks[name].displacement[i])[s]
            p = X0 + (origin + surface + scale * D) @ A.T
            if len(tri):
                faces = Poly3DCollection(p[tri], cmap=ELEVATION_CMAP, norm=self.elevation, alpha=0.9,
                                         linewidth=0.2, edgecolor="k")
                faces.set_array(D[:, 2][tri].mean(axis=1))
                ax.add_collection3d(faces)
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
    fig.tight_layout(rect=(0, 0, 0.9, 1))
    tanks.colour_bar(fig, scale)
    with finishing():           # Ctrl-C meanwhile: the figure whole, then exit 130 (run/guard.py)
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
    fig = figure(5.6, 5.0)
    ax = fig.add_axes((0.0, 0.0, 0.88, 0.92), projection="3d")
    fig.suptitle(_surface_title(scale), fontsize=10)
    tanks.colour_bar(fig, scale)

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
