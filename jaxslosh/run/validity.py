"""Whether a run stayed where its model holds: the linear liquid's free surface inside its tank, the
Newton residual at the tolerance. What is found goes into the summary and the result file's
`warnings` attribute (the run itself is not stopped: its numbers may still be what the user wants
to see)."""
from __future__ import annotations

import numpy as np

from ..scene.types import Scene

#: a frame residual this many times the tolerance is reported (the iterations accept a stall at
#: the residual's round-off floor, which large liquid displacements lift)
RESIDUAL_FACTOR = 100.0


class Watch:
    """Extremes seen over the frames of a run, chunk by chunk."""

    def __init__(self, scene: Scene):
        self.scene = scene
        n = len(scene.tanks) if scene.effects.liquid else 0
        self.low = np.full(n, np.inf)
        self.high = np.full(n, -np.inf)
        self.t_low = np.zeros(n)
        self.t_high = np.zeros(n)
        self.residual, self.t_residual = 0.0, 0.0

    def update(self, time, surface, residual):
        """time (k,), surface (k, tanks, 2), residual (k,) of the frames just computed."""
        time = np.asarray(time)
        if time.size == 0:
            return
        surface = np.asarray(surface).reshape(time.size, -1, 2)
        for i in range(self.low.size):
            j, k = int(np.argmin(surface[:, i, 0])), int(np.argmax(surface[:, i, 1]))
            if surface[j, i, 0] < self.low[i]:
                self.low[i], self.t_low[i] = surface[j, i, 0], time[j]
            if surface[k, i, 1] > self.high[i]:
                self.high[i], self.t_high[i] = surface[k, i, 1], time[k]
        residual = np.asarray(residual)
        r = int(np.argmax(residual))
        if residual[r] > self.residual:
            self.residual, self.t_residual = float(residual[r]), float(time[r])

    def warnings(self) -> list[str]:
        out = []
        for i, t in enumerate(self.scene.tanks[:self.low.size]):
            if not np.isfinite(self.low[i]):
                continue
            roof = t.size[2] - t.fill_depth
            where = f"tanks[{i}] ({t.name!r})"
            model = "the multimodal liquid" if t.model == "multimodal" else "the linear liquid"
            if self.high[i] > roof:
                out.append(f"{where}: the free surface rose {self.high[i]:.3g} m at t = {self.t_high[i]:.4g} s, "
                           f"above the roof ({roof:.3g} m of freeboard): {model} is outside its validity")
            if self.low[i] < -t.fill_depth:
                out.append(f"{where}: the free surface fell {-self.low[i]:.3g} m at t = {self.t_low[i]:.4g} s, "
                           f"below the floor ({t.fill_depth:.3g} m deep): {model} is outside its validity")
        tol = self.scene.simulation.tolerance
        if self.residual > RESIDUAL_FACTOR * tol:
            out.append(f"the Newton residual reached {self.residual:.3g} (tolerance {tol:.3g}) at t = "
                       f"{self.t_residual:.4g} s: those steps stopped at round-off far above the tolerance, "
                       f"a sign of displacements beyond the model's range")
        return out
