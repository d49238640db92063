"""Plots of results (matplotlib, headless)."""
from __future__ import annotations

import numpy as np


def plot_result(r, out: str) -> None:
    """Time histories: roll, pitch, heave and the vertical displacement of every probe."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.asarray(r.time)
    rpy = np.asarray(r.vessel.roll_pitch_yaw)
    z = np.asarray(r.vessel.position)[:, 2]
    n_probe = len(r.probes)
    rows = 2 + (1 if n_probe else 0)
    fig, ax = plt.subplots(rows, 1, figsize=(9, 2.6 * rows), sharex=True)
    ax[0].plot(t, np.degrees(rpy[:, 0]), label="roll")
    ax[0].plot(t, np.degrees(rpy[:, 1]), label="pitch")
    ax[0].set_ylabel("angle (deg)")
    ax[0].legend(loc="upper right")
    ax[1].plot(t, z, color="C2")
    ax[1].set_ylabel("heave (m)")
    if n_probe:
        for name, p in r.probes.items():
            ax[2].plot(t, np.asarray(p.displacement)[:, 2], label=f"probe {name}")
        ax[2].set_ylabel("vertical displacement (m)")
        ax[2].legend(loc="upper right")
    ax[-1].set_xlabel("time (s)")
    status = "" if r.status == "ok" else f"  [{r.status}]"
    fig.suptitle(f"jaxslosh result{status}", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def plot_free_surface(r, out: str, times=None, scale: float = 1.0) -> None:
    """The counterpart of the paper's Figure 5(a): the hull's attitude and the deformed free surface
    of every tank at a few instants, in the inertial frame (displacements magnified by `scale`)."""
    import tomllib

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation

    from .kinematics import rotation_matrix

    if not r.tanks:
        raise ValueError("the result holds no liquid fields (run with tanks, without --no-fields)")
    scene = tomllib.loads(r.scene_text)
    origins = {t["name"]: np.asarray(t["origin"], float) for t in scene.get("tanks", [])}
    sizes = {t["name"]: np.asarray(t["size"], float) for t in scene.get("tanks", [])}
    depth = {t["name"]: float(t["fill_depth"]) for t in scene.get("tanks", [])}
    t_all = np.asarray(r.time)
    if times is None:
        times = np.linspace(t_all[0], t_all[-1], 4)
    idx = [int(np.argmin(np.abs(t_all - tt))) for tt in times]
    fig = plt.figure(figsize=(4.2 * len(idx), 4.2))
    span = max(float(np.max(sz)) for sz in sizes.values()) * 0.75
    for j, i in enumerate(idx):
        ax = fig.add_subplot(1, len(idx), j + 1, projection="3d")
        A = np.asarray(rotation_matrix(np.asarray(r.vessel.quaternion[i])))
        X0 = np.asarray(r.vessel.position[i])
        for name, tf in r.tanks.items():
            nodes = np.asarray(tf.nodes)
            D = np.asarray(tf.displacement[i])
            s = np.flatnonzero(np.isclose(nodes[:, 2], depth[name]))
            p = X0 + (origins[name] + nodes[s] + scale * D[s]) @ A.T
            tri = Triangulation(nodes[s, 0], nodes[s, 1])
            ax.plot_trisurf(p[:, 0], p[:, 1], p[:, 2], triangles=tri.triangles, cmap="Blues", alpha=0.9,
                            linewidth=0.2, edgecolor="k")
            lo, hi = origins[name], origins[name] + sizes[name]
            corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
            for a_ in range(8):
                for b_ in range(a_ + 1, 8):
                    if np.sum(np.abs(corners[a_] - corners[b_]) > 1e-12) == 1:
                        seg = X0 + corners[[a_, b_]] @ A.T
                        ax.plot(seg[:, 0], seg[:, 1], seg[:, 2], color="0.3", lw=0.8)
        ax.set_title(f"t = {t_all[i]:.2f} s", fontsize=9)
        c = np.asarray(r.vessel.position[i])
        ax.set_xlim(c[0] - span, c[0] + span)
        ax.set_ylim(c[1] - span, c[1] + span)
        ax.set_zlim(c[2] - span, c[2] + span)
        ax.set_box_aspect((1, 1, 1))
        ax.set_xlabel("X")
        ax.set_ylabel("Y")
        ax.set_zlabel("Z")
    fig.suptitle("tank and free surface in the inertial frame" + (f" (displacements x{scale:g})" if scale != 1 else ""),
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)
