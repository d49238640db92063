"""The step on whatever device JAX has (a GPU where one is lent), in one run: the paper example, a
20 x 20 x 12 box tank, the LNG carrier's shaped tanks, a vmapped batch of the paper example, and one campaign batch (the worker's
`run_batch`: JONSWAP seas of the waves scene, statistics included).

    python -m benchmarks.speed.gpu [--steps 2000] [--batch 64] [--cases 64] [--duration 60] [--quick]

Prints one table: compile (first call less the second) or the first call, the run (second call,
the same shapes) per case, and the microseconds per step (per run-step for batches); the single
scenes' step by benchmarks/harness.py's time_scene. No assertion; tests never time anything.
"""
import time

import jax
import numpy as np

import jaxslosh as js
from benchmarks.harness import Table, parser, scene, time_scene


def twice(f):
    """(first call's wall time, second call's wall time, output): compile plus run, then run."""
    t0 = time.perf_counter()
    out = f()
    jax.block_until_ready(jax.tree_util.tree_leaves(out))
    t1 = time.perf_counter()
    out = f()
    jax.block_until_ready(jax.tree_util.tree_leaves(out))
    return t1 - t0, time.perf_counter() - t1, out


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=2000, help="steps of the paper example (its 20 s)")
    ap.add_argument("--tank-steps", type=int, default=200, help="steps of the 20 x 20 x 12 tank")
    ap.add_argument("--batch-steps", type=int, default=200, help="steps of each run of the batch")
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--cases", type=int, default=64)
    ap.add_argument("--duration", type=float, default=60.0, help="s of each campaign case")
    ap.add_argument("--only", default="paper,tank20,lng,batch,campaign")
    a = ap.parse_args()
    if a.quick:         # a few steps of each, small batches; campaign cases just past the waves' 20 s ramp
        a.steps, a.tank_steps, a.batch_steps, a.batch, a.cases, a.duration = 10, 5, 10, 4, 2, 22.0
        a.only = "paper,batch,campaign" if a.only == ap.get_default("only") else a.only
    only = a.only.split(",")
    dev = jax.devices()[0]
    print(f"device: {dev.platform} {getattr(dev, 'device_kind', '')}, jax {jax.__version__}", flush=True)
    rows = []
    paper = scene("paper_ship_tank")
    dt = paper.simulation.dt
    base = paper
    if "paper" in only:
        t = time_scene("paper", base, a.steps)
        rows.append(("paper example (125 hexahedra)", t.steps, t.compile_s, t.run_s, t.us_per_step,
                     "ok" if t.ok else "failed"))
        print(rows[-1], flush=True)
    if "tank20" in only:
        big = js.scene_with(base, {"tanks[0].mesh": [20, 20, 12]})
        t = time_scene("tank20", big, a.tank_steps)
        rows.append((f"paper ship, 20x20x12 tank ({t.unknowns} unknowns)", t.steps, t.compile_s, t.run_s,
                     t.us_per_step, "ok" if t.ok else "failed"))
        print(rows[-1], flush=True)
    if "lng" in only:
        t = time_scene("lng", scene("lng_carrier"), a.tank_steps)
        rows.append((f"lng_carrier, two prismatic tanks ({t.unknowns} unknowns)", t.steps, t.compile_s,
                     t.run_s, t.us_per_step, "ok" if t.ok else "failed"))
        print(rows[-1], flush=True)
    if "batch" in only:
        gm = np.linspace(1.0, 2.0, a.batch)
        short = js.scene_with(base, {"simulation.duration": a.batch_steps * dt})
        c, r, (res, st) = twice(lambda: js.simulate_batch(short, {"vessel.hydrostatics.gm_t": gm}))
        n = a.batch_steps * a.batch
        rows.append((f"paper example, batch of {a.batch}", n, c, r, 1e6 * r / n, f"{st.count('ok')}/{a.batch} ok"))
        print(rows[-1], flush=True)
    if "campaign" in only:
        from jaxslosh.campaign.worker import run_batch
        waves = scene("paper_ship_waves")
        path, text = waves.path, waves.text
        hs = np.linspace(0.5, 2.0, a.cases)
        values = [{"hs": float(h), "tp": 6.0, "heading": float(np.pi / 2), "seed": i} for i, h in enumerate(hs)]
        steps = int(round(a.duration / 0.05))
        c, r, out = twice(lambda: run_batch(text, path, a.duration, values, a.cases))
        ok = sum(o["status"] == "ok" for o in out)
        rows.append((f"campaign batch, {a.cases} cases x {a.duration:g} s", steps * a.cases, c, r,
                     1e6 * r / (steps * a.cases), f"{ok}/{a.cases} ok"))
        print(rows[-1], flush=True)
    print()
    table = Table((f"case ({dev.platform})", "{}"), ("run-steps", "{:d}"), ("compile or first call (s)", "{:.2f}"),
                  ("second call (s)", "{:.3f}"), ("us per run-step", "{:.1f}"), ("status", "{}"))
    for row in rows:
        table.add(*row)
    table.print(a.markdown)


if __name__ == "__main__":
    main()
