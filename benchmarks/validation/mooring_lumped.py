"""Lumped-mass mooring lines: their cost per line and segment, and their fairlead tension against
MoorDyn's for a fairlead driven by a motion record (docs/guide/moorings-lumped.md).

    python -m benchmarks.validation.mooring_lumped                                  # the cost table only
    python -m benchmarks.validation.mooring_lumped --moordyn-python /tmp/mdvenv/bin/python

MoorDyn is never a dependency of jaxslosh or its tests: install it apart, e.g.
`python -m venv /tmp/mdvenv && /tmp/mdvenv/bin/pip install moordyn`, and name that interpreter;
MoorDyn then runs in a subprocess of it, fed the same motion record.

The line is the OC3-Hywind one (depth 320 m, anchor radius 853.87 m, fairlead radius 5.2 m at 70 m
below the water, L = 902.2 m, EA = 384.243 MN, d = 0.09 m, 77.7066 kg/m, Cd 1.6 / 0.1, Ca 1.0 / 0.0,
BA -0.8, seabed 3 MPa/m and 0.3 MPa s/m; the submerged weight (m - rho pi d^2 / 4) g with g = 9.81,
as MoorDyn computes it), 20 segments. The fairlead surges x(t) = A r(t) sin(2 pi t / T), r rising
as (1 - cos) / 2 over the first two periods. jaxslosh steps it at the ship's step h (0.1 s) with its
own sub-steps; MoorDyn is fed the record every 0.01 s (its coupling extrapolates the fairlead with
constant velocity over a coupling step) and integrates at its dtM = 1 ms.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import jaxslosh as js  # noqa: E402
from jaxslosh.mooring import lumped as lm  # noqa: E402
from jaxslosh.mooring.lumped_term import lumped_line_term, with_lines  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
RHO, G = 1025.0, 9.81
OC3 = dict(anchor=(-853.87, 0.0, -320.0), fairlead=(-5.2, 0.0, -70.0), length=902.2, ea=384.243e6,
           diameter=0.09, mass=77.7066, depth=320.0)
WEIGHT = (OC3["mass"] - RHO * math.pi * OC3["diameter"] ** 2 / 4) * G


def oc3_line(segments=20):
    c = OC3
    return lm.lumped_line(c["anchor"], c["length"], WEIGHT, c["ea"], segments=segments,
                          diameter=c["diameter"], mass=c["mass"], seabed_z=-c["depth"], rho=RHO, gravity=G)


def timed(f, *args, repeat=3):
    jax.block_until_ready(f(*args))
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(f(*args))
        best = min(best, time.perf_counter() - t0)
    return best


# ---------------------------------------------------------------------------- cost
def line_alone_cost(h=0.1, n_steps=500):
    rows = []
    f0 = jnp.array(OC3["fairlead"])
    for n in (10, 20, 40):
        line = oc3_line(n)
        r, _ = lm.static_shape(line, f0)
        s0 = lm.LineState(r, jnp.zeros_like(r))
        z3 = jnp.zeros(3)

        @jax.jit
        def run(s, line=line):
            return jax.lax.scan(lambda s, _: (lm.advance(line, s, f0, z3, f0, z3, h), None), s, None,
                                length=n_steps)[0]

        t = timed(run, s0) / n_steps
        k = line.substeps(h)
        rows.append((n, k, t * 1e6, t * 1e6 / n, t * 1e9 / (n * k)))
    print(f"\nOne line alone (lumped.advance), ship step h = {h} s, {jax.devices()[0].platform}:")
    print("| segments | sub-steps per step | us per step | us per step and segment | ns per sub-step and segment |")
    print("|---:|---:|---:|---:|---:|")
    for n, k, t, ts, tss in rows:
        print(f"| {n} | {k} | {t:.1f} | {ts:.2f} | {tss:.1f} |")


def moored_stepper(lines, segments, dt=0.1):
    scene = js.scene_with(js.load_scene(os.path.join(HERE, "..", "scenes", "vessel_only.toml")),
                          {"vessel.initial.angular_velocity": [0.0, 0.0, 0.0],
                           "vessel.initial.velocity": [0.5, 0.0, 0.0], "simulation.dt": dt})
    st = js.Stepper(scene)
    if not lines:
        return st
    c = OC3
    terms = []
    for i in range(lines):
        ang = 2 * math.pi * i / lines
        rot = np.array([[math.cos(ang), -math.sin(ang)], [math.sin(ang), math.cos(ang)]])
        fx, fy = rot @ np.array(c["fairlead"][:2])
        ax, ay = rot @ np.array(c["anchor"][:2])
        terms.append(lumped_line_term(st.built.c0, dt, name=f"line{i + 1}", fairlead=[fx, fy, -70.0],
                                      anchor=[ax, ay, -320.0], length=c["length"], weight=WEIGHT, ea=c["ea"],
                                      depth=c["depth"], mass=c["mass"], segments=segments,
                                      gravity=G, water_density=RHO))
    return with_lines(st, terms)


def vessel_cost(n_steps=200):
    cases = [(0, 0), (1, 20), (3, 20), (3, 40)]
    rows = []
    for lines, seg in cases:
        st = moored_stepper(lines, seg)
        s0 = st.init()
        t = timed(lambda s: st.advance(s, n_steps), s0) / n_steps
        s1 = st.advance(s0, n_steps)
        rows.append((lines, seg, t * 1e3, st.status(s1), int(s1.iterations) if hasattr(s1, "iterations") else None))
    base = rows[0][2]
    print(f"\nThe rigid ship of scenes/vessel_only.toml at dt = 0.1 s (Stepper.advance, {n_steps} steps), "
          f"{jax.devices()[0].platform}:")
    print("| lines | segments | ms per step | added ms per line | added us per line and segment | status |")
    print("|---:|---:|---:|---:|---:|---|")
    for lines, seg, t, status, _ in rows:
        add = (t - base) / lines if lines else 0.0
        per = add * 1e3 / seg if lines else 0.0
        print(f"| {lines} | {seg} | {t:.3f} | {add:.3f} | {per:.1f} | {status} |")


# ---------------------------------------------------------------------------- MoorDyn
MOORDYN_INPUT = """--------------------- MoorDyn Input File ------------------------------------
OC3-Hywind line, fairlead driven by a motion record (jaxslosh benchmarks/validation/mooring_lumped.py)
----------------------- LINE TYPES ------------------------------------------
TypeName   Diam     Mass/m     EA         BA/-zeta    EI     Cd     Ca    CdAx    CaAx
(name)     (m)      (kg/m)     (N)        (N-s/-)    (N-m^2) (-)    (-)   (-)     (-)
main       {d}     {m}    {ea}  -0.8        0      1.6    1.0   0.1     0.0
---------------------- POINTS --------------------------------
ID    Attachment     X       Y      Z      Mass   Volume  CdA    Ca
(-)   (-)           (m)     (m)    (m)    (kg)   (m^3)   (m^2)  (-)
1     Fixed       {ax}   {ay}   {az}   0      0       0      0
2     Coupled     {fx}   {fy}   {fz}    0      0       0      0
---------------------- LINES --------------------------------------
ID   LineType   AttachA  AttachB  UnstrLen  NumSegs  LineOutputs
(-)   (-)        (-)      (-)      (m)       (-)       (-)
1    main       1        2        {L}     {n}        -
---------------------- OPTIONS -----------------------------------------
0.001     dtM
3.0e6     kbot
3.0e5     cbot
1.0       dtIC
100       TmaxIC
4.0       CdScaleIC
0.0001    threshIC
{depth}       WtrDpth
{rho}      WtrDnsty
------------------------- need this line --------------------------------------
"""

MOORDYN_DRIVER = r"""
import json, sys, numpy as np, moordyn
d = json.load(open(sys.argv[1]))
s = moordyn.Create(d["input"])
x, v = np.array(d["x"]), np.array(d["v"])
moordyn.Init(s, x[0], v[0])
dt, out, T = d["dt"], [], []
for k in range(len(x) - 1):
    f = moordyn.Step(s, x[k], v[k], k * dt, dt)
    T.append(list(f))
moordyn.Close(s)
json.dump({"force": T}, open(sys.argv[2], "w"))
"""


def motion(t, amp, period):
    w = 2 * np.pi / period
    ramp_t = 2 * period
    tau = np.clip(t / ramp_t, 0.0, 1.0)
    r = 0.5 * (1 - np.cos(np.pi * tau))
    rd = np.where(t < ramp_t, 0.5 * np.pi / ramp_t * np.sin(np.pi * tau), 0.0)
    x = amp * r * np.sin(w * t)
    v = amp * (rd * np.sin(w * t) + r * w * np.cos(w * t))
    return x, v


def jaxslosh_tensions(t_ship, amp, period, h, segments=20):
    line = oc3_line(segments)
    f0 = jnp.array(OC3["fairlead"])
    r, _ = lm.static_shape(line, f0)
    x, v = motion(np.asarray(t_ship), amp, period)
    ex = jnp.array([1.0, 0.0, 0.0])
    P = f0 + jnp.asarray(x)[:, None] * ex
    U = jnp.asarray(v)[:, None] * ex

    def body(s, k):
        s = lm.advance(line, s, P[k], U[k], P[k + 1], U[k + 1], h)
        return s, lm.fairlead_force(line, s.r, s.v, P[k + 1], U[k + 1])

    s0 = lm.LineState(r, jnp.zeros_like(r))
    F0 = lm.fairlead_force(line, r, jnp.zeros_like(r), f0, jnp.zeros(3))
    _, F = jax.jit(lambda s: jax.lax.scan(body, s, jnp.arange(len(t_ship) - 1)))(s0)
    return np.concatenate([np.asarray(F0)[None], np.asarray(F)])


def moordyn_tensions(python, t_end, amp, period, dt=0.01, segments=20):
    c = OC3
    with tempfile.TemporaryDirectory() as tmp:
        inp = os.path.join(tmp, "line.dat")
        with open(inp, "w") as f:
            f.write(MOORDYN_INPUT.format(d=c["diameter"], m=c["mass"], ea=c["ea"], ax=c["anchor"][0],
                                         ay=c["anchor"][1], az=c["anchor"][2], fx=c["fairlead"][0],
                                         fy=c["fairlead"][1], fz=c["fairlead"][2], L=c["length"],
                                         n=segments, depth=c["depth"], rho=RHO))
        t = np.arange(int(round(t_end / dt)) + 2) * dt
        x, v = motion(t, amp, period)
        X = np.array(c["fairlead"])[None] + x[:, None] * np.array([1.0, 0.0, 0.0])
        V = v[:, None] * np.array([1.0, 0.0, 0.0])
        with open(os.path.join(tmp, "in.json"), "w") as f:
            json.dump({"input": inp, "x": X.tolist(), "v": V.tolist(), "dt": dt}, f)
        drv = os.path.join(tmp, "drive.py")
        with open(drv, "w") as f:
            f.write(MOORDYN_DRIVER)
        t0 = time.perf_counter()
        subprocess.run([python, drv, os.path.join(tmp, "in.json"), os.path.join(tmp, "out.json")],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=tmp)
        wall = time.perf_counter() - t0
        F = np.array(json.load(open(os.path.join(tmp, "out.json")))["force"])
    # Step(x_k, v_k, t_k, dt) returns the force at t_{k+1}
    return t[1:len(F) + 1], F, wall


def compare(python, amp=5.0, period=12.0, t_end=72.0, h=0.1, every=1.0):
    n = int(round(t_end / h))
    t_ship = np.arange(n + 1) * h
    t0 = time.perf_counter()
    Fj = jaxslosh_tensions(t_ship, amp, period, h)
    wall_j = time.perf_counter() - t0
    tm, Fm, wall_m = moordyn_tensions(python, t_end, amp, period)
    Tj = np.linalg.norm(Fj, axis=1)
    Tm = np.interp(t_ship, tm, np.linalg.norm(Fm, axis=1))
    print(f"\nFairlead tension (kN), OC3-Hywind line, 20 segments, surge {amp} m at {period} s "
          f"(ramped over {2 * period:.0f} s); jaxslosh h = {h} s, MoorDyn coupling 0.01 s / dtM 1 ms:")
    print("| t (s) | fairlead x (m) | jaxslosh | MoorDyn | difference | difference / MoorDyn's range |")
    print("|---:|---:|---:|---:|---:|---:|")
    win = t_ship >= 4 * period
    rng = Tm[win].max() - Tm[win].min()
    for k in range(0, n + 1, int(round(every / h))):
        if t_ship[k] < t_end - period - 1e-9:      # the last cycle
            continue
        x, _ = motion(t_ship[k], amp, period)
        d = Tj[k] - Tm[k]
        print(f"| {t_ship[k]:.1f} | {float(x):+.2f} | {Tj[k] / 1e3:.1f} | {Tm[k] / 1e3:.1f} | {d / 1e3:+.1f} | "
              f"{100 * d / rng:+.1f} % |")
    print(f"\nAt rest (t = 0): jaxslosh {Tj[0] / 1e3:.2f} kN, MoorDyn {np.linalg.norm(Fm[0]) / 1e3:.2f} kN (after "
          f"its first 0.01 s step).")
    print(f"Steady cycles (t >= {4 * period:.0f} s): jaxslosh min/max {Tj[win].min() / 1e3:.1f} / "
          f"{Tj[win].max() / 1e3:.1f} kN, MoorDyn {Tm[win].min() / 1e3:.1f} / {Tm[win].max() / 1e3:.1f} kN; "
          f"RMS difference {np.sqrt(np.mean((Tj[win] - Tm[win]) ** 2)) / 1e3:.2f} kN = "
          f"{100 * np.sqrt(np.mean((Tj[win] - Tm[win]) ** 2)) / rng:.2f} % of MoorDyn's range, max "
          f"{np.abs(Tj[win] - Tm[win]).max() / 1e3:.2f} kN.")
    print(f"Wall time for {t_end:.0f} s: jaxslosh {wall_j:.2f} s (with compilation), MoorDyn {wall_m:.2f} s "
          f"(with its 100 s static relaxation and the subprocess).")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--moordyn-python", help="an interpreter with `moordyn` installed (not jaxslosh's)")
    p.add_argument("--no-cost", action="store_true")
    p.add_argument("--amplitude", type=float, default=5.0)
    p.add_argument("--period", type=float, default=12.0)
    a = p.parse_args(argv)
    if not a.no_cost:
        line_alone_cost()
        vessel_cost()
    if a.moordyn_python:
        compare(a.moordyn_python, a.amplitude, a.period)


if __name__ == "__main__":
    sys.exit(main())
