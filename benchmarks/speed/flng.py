"""The FLNG side by side with an LNG carrier (scenes/flng_side_by_side.toml): what its 3-hour sea
state costs, and where its step goes.

    python -m benchmarks.speed.flng [--steps 480] [--repeat 2] [--profile] [--quick] [--markdown]

The scene as shipped: the FLNG and the carrier (12 rigid unknowns, each hull's radiation memory),
eight prismatic cargo tanks on 20 sloshing modes each (four in each hull), eight lumped-mass
chain lines of 20 segments (each sub-stepped inside the step), eight hawsers and four fenders, a
JONSWAP sea of 100 components; dt 0.25 s, so a 3-hour sea state is 43,200 steps. `steps` steps are timed with
`js.Stepper.advance` after compilation (benchmarks/harness.py: best of `repeat`, wall and this
process's CPU time, all threads); the 3-hour sea state's time is extrapolated from that stepping
rate (the step's cost does not depend on the time reached), and printed beside the measured steps.
The goal: under 10 minutes per 3-hour sea state on one core, i.e. 600 CPU seconds.

`--profile` adds the scene without each of its parts, timed round by round with it (the share of
the step each part takes): the lines as quasi-static catenaries, no tanks (their LNG frozen into
the hulls' masses), no connections, no waves. Prints tables; no assertion.
"""
import jaxslosh as js
from benchmarks.harness import Table, machine, parser, scene, time_scene, time_scenes

SEA_STATE = 3 * 3600.0          # s
LUMPED_ONLY = ("mass", "diameter", "cd", "ca")


def variants(sc):
    """The scene without each of its parts: (name, scene)."""
    lines = [m.name for m in sc.mooring]
    catenary = {f"mooring.{n}.model": "catenary" for n in lines}
    catenary.update({f"mooring.{n}.{k}": None for n in lines for k in LUMPED_ONLY})
    # the tanks' LNG frozen into the hulls' masses (so that each still floats at its draft)
    no_tanks = {"tanks": None, "probes": None,
                "vessel.mass": sc.vessel.mass + sum(t.liquid_mass for t in sc.tanks)}
    no_tanks.update({f"bodies.{b.name}.mass": b.mass + sum(t.liquid_mass for t in b.tanks) for b in sc.bodies})
    return [
        ("as shipped", sc),
        ("lines as catenaries", js.scene_with(sc, catenary)),
        ("no tanks", js.scene_with(sc, no_tanks)),
        ("no connections", js.scene_with(sc, {"connections": None})),
        ("no waves", js.scene_with(sc, {"waves": None})),
    ]


def main():
    ap = parser(__doc__)
    ap.add_argument("--steps", type=int, default=480, help="steps timed (480: 2 minutes of the sea state)")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--profile", action="store_true", help="also time the scene without each of its parts")
    a = ap.parse_args()
    steps = 40 if a.quick else a.steps
    sc = scene("flng_side_by_side")
    dt = sc.simulation.dt
    n_sea = round(SEA_STATE / dt)
    print(machine())
    r = time_scene("flng_side_by_side", sc, steps, repeat=a.repeat)
    per_step_cpu, per_step_wall = r.cpu_s / steps, r.run_s / steps
    table = Table(("measured", "{}"), ("steps", "{:d}"), ("simulated s", "{:.0f}"), ("wall s", "{:.2f}"),
                  ("CPU s", "{:.2f}"), ("CPU ms/step", "{:.2f}"), ("status", "{}"),
                  title=f"{r.unknowns} unknowns; build {r.build_s:.1f} s, compile {r.compile_s:.1f} s")
    table.add("timed steps", steps, steps * dt, r.run_s, r.cpu_s, 1e3 * per_step_cpu, "ok" if r.ok else "FAILED")
    table.print(markdown=a.markdown)
    print()
    ext = Table(("extrapolated", "{}"), ("steps", "{:d}"), ("wall min", "{:.1f}"), ("CPU min", "{:.1f}"),
                ("CPU s per simulated hour", "{:.0f}"), ("real time / CPU time", "{:.1f}"))
    ext.add("3-hour sea state", n_sea, n_sea * per_step_wall / 60, n_sea * per_step_cpu / 60,
            3600 / dt * per_step_cpu, dt / per_step_cpu)
    ext.print(markdown=a.markdown)
    print(f"goal: 10 CPU minutes per 3-hour sea state: {'met' if n_sea * per_step_cpu <= 600 else 'missed'} "
          f"({n_sea * per_step_cpu / 60:.1f} min)")
    if not a.profile:
        return
    print()
    recs = time_scenes(variants(sc), steps, repeat=a.repeat, progress=lambda s: print(" ", s, flush=True))
    base = recs[0].cpu_s
    prof = Table(("scene", "{}"), ("unknowns", "{:d}"), ("CPU ms/step", "{:.2f}"), ("/ as shipped", "{:.2f}"),
                 ("the part's share", "{}"), title="where the step goes (one run, rounds interleaved)")
    for rec in recs:
        share = "" if rec is recs[0] else f"{100 * (1 - rec.cpu_s / base):.0f} %"
        prof.add(rec.name, rec.unknowns, 1e3 * rec.cpu_s / steps, rec.cpu_s / base, share)
    prof.print(markdown=a.markdown)


if __name__ == "__main__":
    main()
