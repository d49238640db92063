"""KG from a roll decay (docs/guide/identification.md, issue 32 item 6): a box barge (20 x 10 m,
draft 3 m, depth 6 m, KG 3.6 m, GM0 0.678 m) released at several heels, its roll decay (linear
roll damping of about 7 % of critical, 16 s at dt = 0.1 s) recorded with noise (0.2 degrees on
roll and pitch, 5 mm on heave; several seeds), then fitted two ways:

- `--fit vessel.hull.kg` with the nonlinear hydrostatics (started at KG 3.5 m; every channel,
  weights 1 / noise), which reports the implied GM0 = KM - KG;
- `--fit vessel.hydrostatics.gm_t` with the GM springs (`model = "linear"`, started at the
  hull's GM0 for KG 3.5 m; the roll alone, which is all the springs can follow), and the KG that
  GM implies, KM - GM.

    python -m benchmarks.validation.kg_identification [--angles 10,20,28] [--seeds 3] [--out DIR] [--quick]

Prints a table: per release heel the mean (and spread over the seeds) of each fit's error against
the record's true KG and GM0. With --out, also writes the 28-degree case's files (barge.toml,
barge_linear.toml, measured.h5) and prints the `jaxslosh identify` commands that fit them. The
barge, its true KG and the record's noise are the test's (tests/fit/test_identify_kg.py; run from
the repository root); the noise is jaxslosh/fit/problem.add_noise's, as `jaxslosh identify`'s
tests draw it. `--quick`: one heel (10 degrees), one seed.
"""
import math
import os
import warnings

import numpy as np

import jaxslosh as js
from jaxslosh.fit.problem import add_noise
from benchmarks.harness import Table, parser
# the barge, its true KG and the record's noise are the test's
from tests.fit.test_identify_kg import B, BARGE, KM, L, MASS, NOISE, T, TRUE_KG

START_KG = 3.5


def barge(kg, roll, model="nonlinear"):
    return BARGE.format(mass=MASS, kg=kg, model=model, roll=roll)


def fits(angle_deg, seeds):
    roll = math.radians(angle_deg)
    clean = js.simulate(js.load_scene(barge(TRUE_KG, roll)))
    nonlinear = js.load_scene(barge(START_KG, roll))
    linear = js.load_scene(barge(START_KG, roll, "linear"))
    kg, gm = [], []
    for seed in range(seeds):
        measured = add_noise(clean, NOISE, seed=seed)
        f = js.identify(nonlinear, measured, ["vessel.hull.kg"], weights={c: 1 / s for c, s in NOISE.items()})
        kg.append((f.values["vessel.hull.kg"], f.standard_errors["vessel.hull.kg"], f.converged))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            g = js.identify(linear, measured, ["vessel.hydrostatics.gm_t"], weights={"roll": 1 / NOISE["roll"]},
                            data_scene="ignore")
        gm.append((g.values["vessel.hydrostatics.gm_t"], g.standard_errors["vessel.hydrostatics.gm_t"], g.converged,
                   g.residual_to_noise["roll"]))
    return np.array(kg), np.array(gm)


def write_case(out):
    os.makedirs(out, exist_ok=True)
    roll = math.radians(28.0)
    for name, model in (("barge.toml", "nonlinear"), ("barge_linear.toml", "linear")):
        with open(os.path.join(out, name), "w") as f:
            f.write(barge(START_KG, roll, model))
    clean = js.simulate(js.load_scene(barge(TRUE_KG, roll)))
    data = os.path.join(out, "measured.h5")
    js.save_result(add_noise(clean, NOISE, seed=0), data)
    print(f"\nwrote {out}/barge.toml, barge_linear.toml (KG {START_KG} m) and measured.h5 (KG {TRUE_KG} m, noise):")
    print(f"  jaxslosh identify {out}/barge.toml --data {data} --fit vessel.hull.kg")
    print(f"  jaxslosh identify {out}/barge_linear.toml --data {data} --fit vessel.hydrostatics.gm_t "
          "--data-scene ignore")


def main():
    ap = parser(__doc__)
    ap.add_argument("--angles", default="10,20,28", help="release heels, degrees (default 10,20,28)")
    ap.add_argument("--seeds", type=int, default=3, help="noise seeds per heel (default 3)")
    ap.add_argument("--out", help="also write the 28-degree case's scene and record files here")
    a = ap.parse_args()
    if a.quick:
        a.angles, a.seeds = "10", 1
    gm0 = KM - TRUE_KG
    print(f"box barge {L} x {B} m, draft {T} m: KM {KM:.4f} m, true KG {TRUE_KG} m, GM0 {gm0:.4f} m; "
          f"{a.seeds} noise seeds per heel\n")
    table = Table(("release heel", "{}"), ("KG fit (nonlinear), m", "{:.4f}"), ("KG error", "{}"),
                  ("KG std. error", "{:.4f}"), ("GM fit (springs), m", "{:.4f}"), ("GM bias", "{}"),
                  ("KG = KM - GM, m", "{:.4f}"), ("its KG error", "{}"), ("springs' roll residual / noise", "{}"))
    for angle in (float(x) for x in a.angles.split(",")):
        kg, gm = fits(angle, a.seeds)
        ekg = (kg[:, 0] - TRUE_KG) / TRUE_KG * 100
        bias = (gm[:, 0] - gm0) / gm0 * 100
        kg_s = KM - gm[:, 0]
        ekg_s = (kg_s - TRUE_KG) / TRUE_KG * 100
        ok = "" if kg[:, 2].all() and gm[:, 2].all() else " (a fit did not converge)"
        table.add(f"{angle:g} deg", kg[:, 0].mean(), f"{ekg.mean():+.3f} % (max {np.abs(ekg).max():.3f} %)",
                  kg[:, 1].mean(), gm[:, 0].mean(), f"{bias.mean():+.1f} %", kg_s.mean(), f"{ekg_s.mean():+.2f} %",
                  f"{gm[:, 3].mean():.1f}{ok}")
    table.print(a.markdown)
    if a.out:
        write_case(a.out)


if __name__ == "__main__":
    main()
