"""The multimodal and the linear finite-element tank against a laboratory sloshing experiment:
Faltinsen, Rognebakke, Lukovsky & Timokha (2000, J. Fluid Mech. 407), figure 7, the wave elevation
0.05 m from the wall of a 1.73 m tank filled to 0.6 m and moved in surge by 0.032 m with period
1.3 s, from rest (scenes/sloshing_experiment.toml; the measured elevation, as digitised by the PySPH
project, in benchmarks/data/faltinsen2000_fig7.csv).

    python -m benchmarks.validation.sloshing_experiments [--plot docs/sloshing_experiment.png] [--quick]

Prints, for each tank model, over the measured window (0.1 to 9.9 s): the rms difference from the
measurement (the model interpolated at the measured times) over the measured maximum; the error of
the largest crest and of the deepest trough over the measured maximum; and the ratio of the largest
crest to the deepest trough. At the documented forcing it adds the independent fully nonlinear
potential flow (the high-order spectral solution of tests/hos_sloshing.py). A second case repeats
the runs with the forcing amplitude that makes the first trough (before 0.8 s, where the motion is
still linear and the tank models agree) the measured one: a calibration on the first half-period,
the other nine seconds predicted; a third adds to it the laminar boundary-layer damping (ratio
0.003) that the tank's walls give the first mode.

After the documented forcing's rows it prints each record's components over the scored window
(tests/record_components.py: the forced wave, the free first mode and their second-order products,
frequencies fitted): what the rig's start sets (the free wave against the forced one) apart from what
the liquid does with them.

The rig's start-up is not published, so the cases after the first identify it on the first half-period
alone (t < 0.8 s, the first trough: the linear regime, where linear theory, the multimodal tank and the
fully nonlinear potential flow agree), by least squares with the closed form of linear theory (60
standing waves, independent of every tank model), and then give the same forcing to every model and
score it on the rest of the record (0.8 to 9.9 s), which no fit has seen:

- the amplitude that makes the first trough the measured one (the tank moved by a clean harmonic
  start of a smaller amplitude);
- an amplitude and a delay (the tank at rest until the delay, then the harmonic start);
- at the documented amplitude, an excitation frequency that starts at w0 and relaxes to 2 pi / 1.3 s
  with a time constant tau (the rig's period varying at the start: a motion record through
  `[vessel.forced] file`).

    python -m benchmarks.validation.sloshing_experiments --floor

adds a diagnostic that is not a prediction: the multimodal tank's scored rms at the amplitude that
minimises it (one batch over amplitudes, chosen on the scored window itself), the least any clean
harmonic start can reach.

The fully nonlinear potential flow and the records' components are the tests' (tests/hos_sloshing.py,
tests/record_components.py; run from the repository root). `--quick`: the documented forcing's
multimodal and finite-element rows only."""
from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from scipy.optimize import minimize
from scipy.signal import fftconvolve

import jaxslosh as js
from benchmarks.harness import ROOT as _ROOT, parser
from tests.hos_sloshing import hos_tank
from tests.record_components import COMPONENTS, components, fitted_components

ROOT = Path(_ROOT)
SCENE = ROOT / "scenes" / "sloshing_experiment.toml"
DATA = ROOT / "benchmarks" / "data" / "faltinsen2000_fig7.csv"
# the linear finite elements of the same liquid: 16 x 1 x 6 hexahedra (its first and third modes within 0.2 %
# of linear theory's)
FEM = {"tanks[0].model": None, "tanks[0].modes": None, "tanks[0].mesh": [16, 1, 6], "tanks[0].walls": "rigid"}
#: the laminar boundary layers' damping ratio of the first mode (Stokes layers on the bottom, the end and
#: the side walls of the 0.2 m wide tank: 0.002; 0.004 were it 0.1 m wide)
WALL_DAMPING = 0.003
#: the first half-period: the first trough, 0.04 m, in the linear regime (the fit window; the rest is scored)
EARLY = 0.8
L, H, G, A, W, X = 1.73, 0.6, 9.81, 0.032, 2 * np.pi / 1.3, 0.05
DT = 0.002
T = np.arange(0.0, 10.0 + DT / 2, DT)


def measured():
    """(t, elevation) of the experiment, as digitised (uneven in time)."""
    rows = [line.split(",") for line in DATA.read_text().splitlines()
            if line.strip() and not line.startswith("#")]
    assert rows[0] == ["t", "elevation"], rows[0]
    d = np.array(rows[1:], dtype=float)
    return d[:, 0], d[:, 1]


def experiment_scene(model="multimodal", amplitude=0.032, duration=None, damping=0.0, record=None) -> js.Scene:
    """The experiment's scene: the harmonic forcing of `amplitude`, or the motion record file `record`."""
    keys = {}
    if record is not None:
        keys.update({"vessel.forced": None, "vessel.forced.file": str(record)})
    else:
        keys["vessel.forced.amplitude"] = amplitude
    if model == "fem":
        keys.update(FEM)
    elif damping:
        keys["tanks[0].damping.ratio"] = damping
    if duration is not None:
        keys["simulation.duration"] = duration
    return js.scene_with(js.load_scene(str(SCENE)), keys)


def elevation(sc):
    """The probe's elevation history of a run of the scene."""
    r = js.simulate(sc, throw=False)
    if r.status != "ok":
        raise SystemExit(f"run failed: {r.status}")
    return np.asarray(r.time), np.asarray(r.probes["wall"].displacement)[:, 2]


def errors(t, z, tm, zm):
    """rms difference, crest error, trough error (all over the measured maximum) and the ratio of the
    largest crest to the deepest trough, over the whole measured window (the notebook's table)."""
    zi = np.interp(tm, t, z)
    window = (t >= tm[0]) & (t <= tm[-1])
    top = zm.max()
    return (np.sqrt(np.mean((zi - zm) ** 2)) / top, (z[window].max() - zm.max()) / top,
            (z[window].min() - zm.min()) / top, z[window].max() / -z[window].min())


def scored_errors(t, z, tm, zm):
    """rms difference over the fit window and over the scored window, crest error, trough error (all over
    the measured maximum) and the ratio of the largest crest to the deepest trough, over the scored
    window."""
    zi = np.interp(tm, t, z)
    early = tm < EARLY
    window = (t >= EARLY) & (t <= tm[-1])
    top = zm.max()

    def rms(sel):
        return np.sqrt(np.mean((zi[sel] - zm[sel]) ** 2)) / top
    return (rms(early), rms(~early), (z[window].max() - zm[~early].max()) / top,
            (z[window].min() - zm[~early].min()) / top, z[window].max() / -z[window].min())


def record_components(t, z, t0=EARLY, t1=9.9, w=None):
    """The record's components (tests/record_components.py) over t0 to t1, its two frequencies
    fitted from the forcing's and linear theory's first mode's unless given."""
    if w is not None:
        return components(t, z, t0, t1, w)
    k = np.pi / L
    return fitted_components(t, z, t0, t1, [W, np.sqrt(G * k * np.tanh(k * H))])


def linear_theory(acceleration, n=60):
    """The elevation at the probe (on T) of linear theory, the tank at rest at t = 0 and moved along its
    length with `acceleration` (on T): each standing wave cos(k_n x) obeys
    beta_n'' + w_n^2 beta_n = -(c_n / m_n) a(t) (c_n the integral of x cos(k_n x) over the length, m_n
    the mode's mass per unit rho b), solved by convolution with sin(w_n t) / w_n."""
    k = np.arange(1, n + 1) * np.pi / L
    wn = np.sqrt(G * k * np.tanh(k * H))
    c = ((-1.0) ** np.arange(1, n + 1) - 1.0) / k ** 2
    mn = 0.5 * L / (k * np.tanh(k * H))
    # the trapezoidal rule (the end at t carries sin 0 = 0, the one at 0 half its weight)
    beta = np.array([(fftconvolve(acceleration, np.sin(w * T))[:T.size] - 0.5 * acceleration[0] * np.sin(w * T)) / w
                     for w in wn]) * DT
    return np.cos(k * X) @ (-(c / mn)[:, None] * beta)


def harmonic_acceleration(amplitude, delay=0.0):
    """x = amplitude cos(W (t - delay)) from rest at t = delay."""
    return np.where(T >= delay, -amplitude * W ** 2 * np.cos(W * (T - delay)), 0.0)


def varying_period(w0, tau):
    """The phase of an excitation whose frequency starts at w0 and relaxes to W with time constant
    tau, and its first two derivatives (functions of t)."""
    def phase(t):
        return W * t - (W - w0) * tau * (1.0 - np.exp(-t / tau))

    def rate(t):
        return W - (W - w0) * np.exp(-t / tau)

    def rate2(t):
        return (W - w0) / tau * np.exp(-t / tau)
    return phase, rate, rate2


def varying_period_acceleration(w0, tau, t=T):
    phase, rate, rate2 = varying_period(w0, tau)
    return -A * (rate(t) ** 2 * np.cos(phase(t)) + rate2(t) * np.sin(phase(t)))


def identify(model, start, tm, zm):
    """Least squares of linear theory against the measurement over the fit window (t < EARLY) alone."""
    early = tm < EARLY

    def misfit(p):
        return np.sqrt(np.mean((np.interp(tm[early], T, linear_theory(model(p))) - zm[early]) ** 2))
    return minimize(misfit, start, method="Nelder-Mead", options={"xatol": 1e-5, "fatol": 1e-8}).x


def write_record(path, w0, tau):
    """The varying-period surge x = A cos(phase(t)) as a motion record, every 0.005 s from -0.05 s (at
    rest) to 10.05 s."""
    t = np.arange(-0.05, 10.05 + 1e-9, 0.005)
    x = A * np.cos(varying_period(w0, tau)[0](np.maximum(t, 0.0)))
    Path(path).write_text("t,surge\n" + "".join(f"{a:.4f},{b:.10e}\n" for a, b in zip(t, x)))


def shifted(t, z, delay):
    """A run started `delay` later (the tank at rest until then): the liquid's response is invariant in time."""
    return t, np.interp(t - delay, t, z, left=0.0)


def main():
    ap = parser(__doc__)
    ap.add_argument("--plot", help="write the elevation histories to this PNG")
    ap.add_argument("--floor", action="store_true",
                    help="add the multimodal tank's least scored rms over clean harmonic starts (a diagnostic)")
    args = ap.parse_args()
    tm, zm = measured()
    scored = tm >= EARLY
    print(f"measured: largest crest {zm.max():.4f} m, deepest trough {zm.min():.4f} m, "
          f"crest / trough {zm.max() / -zm.min():.2f}; fit window t < {EARLY} s ({np.sum(~scored)} points), "
          f"scored window {EARLY} to {tm[-1]} s ({np.sum(scored)} points)")
    print(f"{'forcing':<44} {'tank':<28} {'rms fit':>8} {'rms scored':>11} {'crest':>8} {'trough':>8} "
          f"{'crest/trough':>13} {'first trough':>13}")
    print(f"{'measured':<44} {'':<28} {'':>8} {'':>11} {'':>8} {'':>8} {zm[scored].max() / -zm[scored].min():>13.2f} "
          f"{zm[tm < EARLY].min():>12.4f}m")
    runs, scores = {}, {}

    def row(case, label, t, z):
        runs[case, label] = (t, z)
        early, rms, crest, trough, ratio = scored_errors(t, z, tm, zm)
        scores[case, label] = rms
        print(f"{case:<44} {label:<28} {100 * early:>7.1f}% {100 * rms:>10.1f}% {100 * crest:>+7.1f}% "
              f"{100 * trough:>+7.1f}% {ratio:>13.2f} {z[t < EARLY].min():>12.4f}m", flush=True)

    def hos(acceleration):
        return hos_tank(L, H, G, acceleration, 10.0, 0.01, X)

    mm, fem, nl = "multimodal, 8 modes", "linear fem, 16 x 1 x 6", "fully nonlinear (HOS, tests/)"
    documented = "documented: 32 mm from rest"
    for model, label in (("multimodal", mm), ("fem", fem)):
        row(documented, label, *elevation(experiment_scene(model, A)))
    if args.quick:
        return
    row(documented, nl, *hos(lambda s: -A * W ** 2 * np.cos(W * s)))
    print_components(tm, zm, {**{label: tz for (case, label), tz in runs.items() if case == documented},
                              "linear theory (closed form)": (T, linear_theory(harmonic_acceleration(A)))})

    # 1. the amplitude that makes the first trough the measured one
    zl = linear_theory(harmonic_acceleration(A))
    amplitude = round(float(A * zm[tm < EARLY].min() / zl[T < EARLY].min()), 4)
    case = f"first trough: amplitude {1000 * amplitude:.1f} mm"
    for model, label in (("multimodal", mm), ("fem", fem)):
        row(case, label, *elevation(experiment_scene(model, amplitude)))
    row(case, nl, *hos(lambda s: -amplitude * W ** 2 * np.cos(W * s)))
    row(case, f"multimodal, damping {WALL_DAMPING}",
        *elevation(experiment_scene("multimodal", amplitude, damping=WALL_DAMPING)))

    # 2. an amplitude and a delay, by least squares on the first half-period
    a2, delay = identify(lambda p: harmonic_acceleration(p[0], p[1]), [0.025, 0.05], tm, zm)
    case = f"fit t<{EARLY}s: {1000 * a2:.1f} mm, delay {delay:.3f} s"
    for model, label in (("multimodal", mm), ("fem", fem)):
        row(case, label, *shifted(*elevation(experiment_scene(model, float(a2))), delay))
    row(case, nl, *shifted(*hos(lambda s: -a2 * W ** 2 * np.cos(W * s)), delay))

    # 3. the documented amplitude, the excitation frequency varying at the start
    w0, tau = identify(lambda p: varying_period_acceleration(p[0], abs(p[1]) + 1e-3), [3.5, 0.5], tm, zm)
    tau = abs(tau) + 1e-3
    case = f"fit t<{EARLY}s: 32 mm, w0 {w0:.2f} rad/s, tau {tau:.2f} s"
    with tempfile.TemporaryDirectory() as tmp:
        record = Path(tmp) / "motion.csv"
        write_record(record, w0, tau)
        for model, label in (("multimodal", mm), ("fem", fem)):
            row(case, label + " (record)", *elevation(experiment_scene(model, record=record)))
    row(case, nl, *hos(lambda s: varying_period_acceleration(w0, tau, s)))

    print("\nthe target, multimodal within 10 % rms of the measured maximum where linear theory is off by more "
          "than 15 % (scored window):")
    for case in dict.fromkeys(c for c, _ in runs):
        m = scores[case, mm] if (case, mm) in scores else scores[case, mm + " (record)"]
        f = scores[case, fem] if (case, fem) in scores else scores[case, fem + " (record)"]
        print(f"  {case:<44} multimodal {100 * m:5.1f} %, linear fem {100 * f:5.1f} %: "
              f"{'met' if m <= 0.10 and f > 0.15 else 'not met'}")

    if args.floor:
        amplitudes = np.round(np.arange(0.021, 0.0296, 0.0015), 4)
        for damping in (0.0, WALL_DAMPING):
            res, status = js.simulate_batch(experiment_scene("multimodal", damping=damping),
                                            {"vessel.forced.amplitude": amplitudes})
            t = np.asarray(res.time)
            t = t[0] if t.ndim == 2 else t
            z = np.asarray(res.probes["wall"].displacement)[..., 2]
            rms = [scored_errors(t, zi, tm, zm)[1] for zi in z]
            i = int(np.argmin(rms))
            print(f"floor (diagnostic, amplitude chosen on the scored window): multimodal, damping {damping}: "
                  f"{100 * rms[i]:.1f} % at {1000 * amplitudes[i]:.1f} mm "
                  f"({', '.join(f'{1000 * a:.1f} mm {100 * r:.1f} %' for a, r in zip(amplitudes, rms))})")

    if args.plot:
        plot(args.plot, runs, tm, zm)


def print_components(tm, zm, records):
    """The components of the measured record and of each model's at the documented forcing, over the
    scored window and (the free wave's) over its two halves: what the rig's start sets (the free wave
    against the forced one) apart from what the liquid does with them (frequencies, products)."""
    half = 0.5 * (EARLY + tm[-1])
    print(f"\ncomponents over {EARLY} to {tm[-1]} s (amplitudes in mm; the free wave also over each half, at the "
          "whole window's frequencies):")
    print(f"{'record':<44} {'w forced':>9} {'w free':>8} " + " ".join(f"{c:>10}" for c in COMPONENTS)
          + f" {'free/forced':>12} {'free, 1st half':>15} {'2nd half':>9}")
    for label, (t, z) in {"measured": (tm, zm), **records}.items():
        w, a, _ = record_components(t, z)
        first = record_components(t, z, EARLY, half, w)[1][1]
        second = record_components(t, z, half, tm[-1], w)[1][1]
        print(f"{label:<44} {w[0]:>9.4f} {w[1]:>8.4f} " + " ".join(f"{1000 * x:>10.1f}" for x in a)
              + f" {a[1] / a[0]:>12.2f} {1000 * first:>15.1f} {1000 * second:>9.1f}")
    print("(every start of a harmonic forcing from rest sets the free wave against the forced one; the "
          "models agree on it, the measured record does not)\n")


def plot(path, runs, tm, zm):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cases = list(dict.fromkeys(c for c, _ in runs))
    fig, axes = plt.subplots(len(cases), 1, figsize=(9, 2.9 * len(cases)), sharex=True)
    for ax, case in zip(axes, cases):
        ax.axvspan(0.0, EARLY, color="0.9", label="fit window" if case != cases[0] else None)
        ax.plot(tm, zm, "k.", ms=4, label="experiment (Faltinsen et al. 2000, fig. 7)")
        for (c, label), (t, z) in runs.items():
            if c == case:
                ax.plot(t, z, lw=1.2, label=label)
        ax.set_ylabel("elevation (m)")
        ax.set_title(f"0.05 m from the wall; forcing {case}", fontsize=10)
        ax.grid(alpha=0.3)
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi + 0.3 * (hi - lo))          # room for the legend above the crests
        ax.legend(fontsize=7, loc="upper left", ncol=3)
    axes[-1].set_xlabel("t (s)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
