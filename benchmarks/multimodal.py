"""The multimodal tank's step cost against the finite-element tank reduced to 20 modes, and against
the full finite-element tank, on the paper example (scenes/paper_ship_tank.toml); and its probe B
against the finite elements'. Prints a table.

    python benchmarks/multimodal.py [--duration T]

Each run is timed twice: the first includes the compilation, the second (the same compiled program)
is the run alone."""
from __future__ import annotations

import argparse
import time

import jax

jax.config.update("jax_enable_x64", True)

import numpy as np  # noqa: E402

import jaxslosh as js  # noqa: E402

VARIANTS = {
    "fem (5x5x5)": lambda t: t,
    "fem, 20 modes": lambda t: t.replace('walls = "rigid"', 'walls = "rigid"\n[tanks.reduction]\nmodes = 20'),
    "multimodal, 6 modes": lambda t: t.replace('mesh = [5, 5, 5]\nwalls = "rigid"', 'model = "multimodal"\nmodes = 6'),
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=20.0)
    args = ap.parse_args()
    text = open("scenes/paper_ship_tank.toml").read()
    rows, zB = [], {}
    for name, edit in VARIANTS.items():
        scene = js.with_overrides(js.load_scene(edit(text)), duration=args.duration) \
            if hasattr(js, "with_overrides") else js.load_scene(edit(text).replace("duration = 20.0",
                                                                                  f"duration = {args.duration}"))
        t0 = time.perf_counter()
        js.simulate(scene)
        first = time.perf_counter() - t0
        t0 = time.perf_counter()
        r = js.simulate(scene)
        run = time.perf_counter() - t0
        n = len(np.asarray(r.time)) - 1
        zB[name] = np.asarray(r.probes["B"].displacement)[:, 2]
        rows.append((name, first - run, 1e3 * run / n, r.status))
    print(f"{'tank':<22} {'compile s':>10} {'ms/step':>9}  status")
    for name, c, ms, st in rows:
        print(f"{name:<22} {c:>10.1f} {ms:>9.3f}  {st}")
    ref = zB["fem (5x5x5)"]
    for name, z in zB.items():
        d = z - ref
        print(f"probe B, {name} vs fem: rms difference / rms {np.sqrt(np.mean(d ** 2) / np.mean(ref ** 2)):.3f}")


if __name__ == "__main__":
    main()
