"""Waves and hull hydrodynamics: Froude-Krylov on a box, JONSWAP, the radiation memory of the Cummins
equation against the frequency domain, Capytaine's hydrostatics, scene validation, effects,
gradients and batches through runs in waves."""
import math
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.assemble.system import build
from jaxslosh.cli import main
from jaxslosh.hydro.radiation import linear_response, restoring_matrix, rigid_mass_matrix
from jaxslosh.hydro.source import radiation_fit
from jaxslosh.hydro.tables import scene_tables
from jaxslosh.solve.integrator import initial_state, step
from jaxslosh.solve.schemes import make_scheme
from jaxslosh.solve.linear import make_solver
from jaxslosh.hydro.box import box_hydrostatics, froude_krylov_box
from jaxslosh.hydro.spectra import components, elevation, jonswap, wavenumber

DATA = Path(__file__).resolve().parents[1] / "data"
RHO, G = 1025.0, 9.81
L, B, T, KG = 20.0, 10.0, 2.0, 2.5
MASS, INERTIA = 4.1e5, (6.0e6, 1.6e7, 2.0e7)


def _tables_text(excitation=True):
    """The Capytaine tables of the test box (tests/data, made by `jaxslosh hydro`), without its
    [vessel.hydrostatics] (the box's closed forms are used), with or without its excitation."""
    text = (DATA / "box_20x10x2_hydro.toml").read_text()
    text = text[text.index("[vessel.hydrodynamics]"):]
    return text if excitation else text[:text.index("\nheadings =")] + "\n"


def box_scene(waves="", duration=10.0, dt=0.05, hydro=True, extra_hydro="", effects="", scheme="newmark",
              excitation=True):
    text = f"""
title = "box barge in waves"
[environment]
gravity = {G}
water_density = {RHO}
[simulation]
duration = {duration}
dt = {dt}
scheme = "{scheme}"
[vessel]
mass = {MASS}
inertia = {list(INERTIA)}
[vessel.hull]
length = {L}
beam = {B}
draft = {T}
kg = {KG}
"""
    if hydro:
        text += _tables_text(excitation).replace("[vessel.hydrodynamics]", "[vessel.hydrodynamics]\n" + extra_hydro)
    return js.load_scene(text + waves + effects)


def regular(omega, amplitude=0.2, heading=math.pi / 2, ramp=20.0):
    return f"""
[waves]
type = "regular"
amplitude = {amplitude}
frequency = {omega!r}
heading = {heading!r}
ramp = {ramp}
"""


def _harmonic(t, x, w):
    """Amplitude and phase of the part of x at frequency w (least squares with a mean and a drift)."""
    M = np.stack([np.cos(w * t), np.sin(w * t), np.ones_like(t), t], axis=1)
    c = np.linalg.lstsq(M, x, rcond=None)[0]
    return complex(c[0], -c[1])       # x = Re(X e^{i w t})


def _reference(scene, omega, X, viscous=None):
    """Frequency-domain response (6,) per unit amplitude with the tables' A(w), B(w) at omega."""
    t = scene_tables(scene.vessel.hydrodynamics)
    i = int(np.argmin(np.abs(t.omega - omega)))
    assert abs(t.omega[i] - omega) < 1e-9
    h = scene.vessel.hydrostatics
    C = restoring_matrix(RHO, G, h.waterplane_area, h.displaced_volume, h.gm_t, h.gm_l)
    Bt = t.damping[i:i + 1] + (0.0 if viscous is None else viscous)
    return linear_response([omega], rigid_mass_matrix(MASS, np.diag(INERTIA)), C, t.added_mass[i:i + 1], Bt,
                           X[None, :])[0]


# --------------------------------------------------------------------------------------------
# Waves and Froude-Krylov (host)


def test_froude_krylov_box_against_quadrature_and_long_wave_limit():
    # brute-force midpoint quadrature of -int p n dS over the five wetted faces
    def brute(w, beta, depth=None, n=120):
        k = wavenumber(w, G, depth)
        kx, ky, zwl = k * np.cos(beta), k * np.sin(beta), T - KG

        def f(z):
            zp = z - zwl
            return np.exp(k * zp) if depth is None else np.cosh(k * (zp + depth)) / np.cosh(k * depth)

        mid = lambda a, b: (a + (np.arange(n) + 0.5) * (b - a) / n, (b - a) / n)  # noqa: E731
        xs, dx = mid(-L / 2, L / 2)
        ys, dy = mid(-B / 2, B / 2)
        zs, dz = mid(-KG, zwl)
        faces = []
        X_, Y_ = np.meshgrid(xs, ys, indexing="ij")
        faces.append((X_, Y_, np.full_like(X_, -KG), (0, 0, -1), dx * dy))
        for s in (1, -1):
            X_, Z_ = np.meshgrid(xs, zs, indexing="ij")
            faces.append((X_, np.full_like(X_, s * B / 2), Z_, (0, s, 0), dx * dz))
            Y_, Z_ = np.meshgrid(ys, zs, indexing="ij")
            faces.append((np.full_like(Y_, s * L / 2), Y_, Z_, (s, 0, 0), dy * dz))
        out = np.zeros(6, complex)
        for x, y, z, nv, dA in faces:
            p = RHO * G * f(z) * np.exp(-1j * (kx * x + ky * y)) * dA
            nv = np.array(nv, float)
            rxn = np.cross(np.stack([x, y, z], -1), nv)
            out += np.concatenate([-(p[..., None] * nv).sum((0, 1)), -(p[..., None] * rxn).sum((0, 1))])
        return out

    for w, beta, depth in [(0.8, math.pi / 2, None), (1.3, 2.0, None), (0.6, 0.3, 15.0)]:
        X = froude_krylov_box(w, beta, L, B, T, KG, RHO, G, depth)[0]
        ref = brute(w, beta, depth)
        assert np.abs(X - ref).max() < 1e-4 * np.abs(ref).max(), (w, beta, X, ref)
    # long waves: the roll moment is the wave slope times the restoring, C44 k sin(beta), 90 deg ahead of eta
    hs = box_hydrostatics(L, B, T, KG)
    C44 = RHO * G * hs["displaced_volume"] * hs["gm_t"]
    w = 0.04
    X = froude_krylov_box(w, math.pi / 2, L, B, T, KG, RHO, G)[0]
    assert abs(X[3] / (C44 * w * w / G) - (-1j)) < 2e-3
    # head seas on a symmetric box: no sway, roll or yaw
    X = froude_krylov_box(np.linspace(0.3, 2, 5), math.pi, L, B, T, KG, RHO, G)
    assert np.abs(X[:, [1, 3, 5]]).max() < 1e-9 * np.abs(X).max()


def test_froude_krylov_box_against_capytaine():
    """Capytaine's Froude-Krylov force on the same box (panel centroids, its e^{-iwt} convention)."""
    import capytaine as cpt
    from jaxslosh.hydro.capytaine import _hull_body
    from jaxslosh.scene.types import BoxHull
    body = _hull_body(cpt, BoxHull(length=L, beam=B, draft=T, kg=KG), 0.5)
    from capytaine.bem.airy_waves import froude_krylov_force
    for w, beta in [(0.7, math.pi / 2), (1.2, 0.6)]:
        pb = cpt.DiffractionProblem(body=body, wave_direction=beta, omega=w, rho=RHO, g=G)
        Fc = froude_krylov_force(pb)
        Xc = np.conj(np.array([Fc[d] for d in body.dofs]))
        X = froude_krylov_box(w, beta, L, B, T, KG, RHO, G)[0]
        for j in range(6):
            if abs(X[j]) > 1e-3 * np.abs(X).max():
                assert abs(Xc[j] / X[j] - 1) < 0.01, (w, beta, j, Xc[j], X[j])


def test_jonswap_spectrum_and_components():
    w = np.linspace(0.05, 30.0, 300001)
    S = jonswap(w, 2.5, 8.0, 3.3)
    assert abs(np.trapezoid(S, w) * 16 / 2.5 ** 2 - 1) < 1e-3
    assert abs(w[np.argmax(S)] - 2 * np.pi / 8.0) < 1e-3
    scene = box_scene(waves='\n[waves]\ntype = "jonswap"\nhs = 2.5\ntp = 8.0\nheading = 1.0\nseed = 7\n'
                            'components = 400\n', hydro=False)
    c = components(scene.waves)
    assert c.omega.size == 400 and np.all(np.diff(c.omega) > 0)
    # variance of the sampled sea: Hs^2 / 16 less the tail beyond 3 wp (about 0.9 %)
    lo, hi = scene.waves.omega_range
    inside = np.trapezoid(np.where((w >= lo) & (w <= hi), S, 0.0), w)
    assert abs(np.sum(c.amplitude ** 2) / 2 / inside - 1) < 0.03
    t = np.arange(0.0, 3600.0, 0.5)
    eta = elevation(scene.waves, t, g=G)
    assert abs(4 * eta.std() / 2.5 - 1) < 0.06
    c2 = components(js.load_scene(scene.text.replace("seed = 7", "seed = 8")).waves)
    assert not np.allclose(c2.phase, c.phase)
    np.testing.assert_array_equal(components(js.load_scene(scene.text).waves).phase, c.phase)


# --------------------------------------------------------------------------------------------
# The radiation memory: the fit, then the time domain against the frequency domain


def test_memory_fit_reproduces_the_tables_over_the_roll_band():
    scene = box_scene()
    t = scene_tables(scene.vessel.hydrodynamics)
    fit = radiation_fit(scene)
    assert np.all(fit.p.real < 0)       # a stable memory
    band = (t.omega >= 0.6) & (t.omega <= 1.6)
    A, Bd = fit.added_mass(t.omega), fit.damping(t.omega)
    # the fit is of the symmetric part (Capytaine's B_24 and B_42 differ by about 3 %)
    At = 0.5 * (t.added_mass + t.added_mass.transpose(0, 2, 1))
    Bt = 0.5 * (t.damping + t.damping.transpose(0, 2, 1))
    for i, j in [(1, 1), (2, 2), (3, 3), (1, 3), (4, 4)]:
        scale = np.abs(Bt[:, i, j]).max()
        assert np.abs(Bd[band, i, j] - Bt[band, i, j]).max() < 0.01 * scale, (i, j)
        assert np.abs(A[band, i, j] - At[band, i, j]).max() < 0.01 * np.abs(At[:, i, j]).max(), (i, j)


def test_regular_beam_wave_roll_matches_the_linear_rao():
    """Box hull alone, Froude-Krylov forces of a regular beam wave, A(w) and B(w) from Capytaine plus a
    viscous roll damping: the steady roll amplitude against |F| / |C - w^2 (M + A) + i w B| (the 6-dof
    form, which couples sway and roll through A and B)."""
    w = 0.9
    Bv = [0.0, 0.0, 0.0, 8.0e5, 0.0, 0.0]
    scene = box_scene(regular(w), duration=180.0,
                      extra_hydro=f'viscous_damping = {Bv}\nexcitation = "froude-krylov"\n')
    r = js.simulate(scene)
    assert r.status == "ok"
    t = np.asarray(r.time)
    keep = t > 100.0
    roll = _harmonic(t[keep], np.asarray(r.vessel.roll_pitch_yaw)[keep, 0], w)
    X = froude_krylov_box(w, math.pi / 2, L, B, T, KG, RHO, G)[0]
    ref = 0.2 * _reference(scene, w, X, viscous=np.diag(Bv)[None])[3]
    ratio = abs(roll) / abs(ref)
    print(f"roll amplitude {abs(roll):.6g} rad, linear RAO {abs(ref):.6g} rad, ratio {ratio:.5f}")
    assert abs(ratio - 1) < 0.02
    # the one-dof formula of the issue, for the record
    t_ = scene_tables(scene.vessel.hydrodynamics)
    i = int(np.argmin(np.abs(t_.omega - w)))
    h = scene.vessel.hydrostatics
    one = abs(0.2 * X[3]) / abs(RHO * G * h.displaced_volume * h.gm_t - w * w * (INERTIA[0] + t_.added_mass[i, 3, 3])
                                  + 1j * w * (t_.damping[i, 3, 3] + Bv[3]))
    print(f"one-dof RAO {one:.6g} rad")
    assert abs(one / abs(ref) - 1) < 0.1     # 5.7 %: sway moves with the roll (A_24, B_24 and the sway force)


def test_cummins_memory_reproduces_the_frequency_domain_roll_response():
    """A harmonic roll moment at frequencies across the roll band (natural frequency ~1.1 rad/s): the
    steady roll and sway against the frequency-domain solution with A(w), B(w) at each frequency."""
    Bv = [0.0, 0.0, 0.0, 6.0e5, 0.0, 0.0]
    M0 = 5.0e4          # N m: roll up to 5 degrees at resonance
    exc = (f"headings = [1.5707963267948966]\nviscous_damping = {Bv}\n"
           f"excitation_amplitude = {[[0, 0, 0, M0, 0, 0]] * 20}\nexcitation_phase = {[[0.0] * 6] * 20}\n")
    errs = []
    far = []
    for w in (0.7, 0.9, 1.1, 1.3, 1.5):
        scene = box_scene(regular(w, amplitude=1.0, ramp=20.0), duration=240.0, extra_hydro=exc, excitation=False)
        r = js.simulate(scene)
        assert r.status == "ok"
        t = np.asarray(r.time)
        keep = t > 140.0
        roll = _harmonic(t[keep], np.asarray(r.vessel.roll_pitch_yaw)[keep, 0], w)
        X = np.array([0, 0, 0, M0, 0, 0], dtype=complex)
        ref = _reference(scene, w, X, viscous=np.diag(Bv)[None])
        errs.append(abs(roll / ref[3] - 1))
        # the same without the memory (A_inf, no radiation damping): what the test would see without it
        fit = radiation_fit(scene)
        h = scene.vessel.hydrostatics
        C = restoring_matrix(RHO, G, h.waterplane_area, h.displaced_volume, h.gm_t, h.gm_l)
        no_mem = linear_response([w], rigid_mass_matrix(MASS, np.diag(INERTIA)), C, fit.added_mass_infinite[None],
                                 np.diag(Bv)[None], X[None])[0]
        far.append(abs(no_mem[3] / ref[3] - 1))
        print(f"w = {w}: roll {abs(roll):.5g} rad, frequency domain {abs(ref[3]):.5g} rad, "
              f"ratio {abs(roll) / abs(ref[3]):.4f}, phase error {np.angle(roll / ref[3]):+.4f} rad; "
              f"without memory off by {far[-1]:.3f}")
    assert max(errs) < 0.03, errs
    assert max(far) > 0.09, far      # the memory matters at these frequencies


# --------------------------------------------------------------------------------------------
# Capytaine


def test_capytaine_box_hydrostatics_equal_the_closed_forms_and_feed_a_scene(tmp_path, capsys):
    from jaxslosh.hydro.capytaine import capytaine_hydrostatics
    from jaxslosh.scene.types import BoxHull
    for (l_, b_, t_, kg) in [(L, B, T, KG), (60.0, 12.0, 4.0, 5.0)]:
        hs = capytaine_hydrostatics(BoxHull(length=l_, beam=b_, draft=t_, kg=kg))
        closed = {"displaced_volume": l_ * b_ * t_, "waterplane_area": l_ * b_, "bm_t": b_ ** 2 / (12 * t_),
                  "bm_l": l_ ** 2 / (12 * t_)}
        for k, v in closed.items():
            assert abs(hs[k] / v - 1) < 0.005, (k, hs[k], v)
        assert abs(hs["gm_t"] - box_hydrostatics(l_, b_, t_, kg)["gm_t"]) < 0.005 * closed["bm_t"]
    # a coarse BEM solve fed to a scene by `jaxslosh hydro`, then run
    p = tmp_path / "box.toml"
    p.write_text((DATA / "box_20x10x2.toml").read_text())
    out = tmp_path / "tables.toml"
    assert main(["hydro", str(p), "--frequencies", "0.4:1.6:6", "--headings", "1.5707963267948966",
                 "--panel-size", "2.0", "-o", str(out)]) == 0
    text = p.read_text().replace("[vessel.hull]", out.read_text() + "\n[vessel.hull]") + regular(1.0, ramp=5.0)
    scene = js.load_scene(text)
    assert abs(scene.vessel.hydrostatics.gm_t - box_hydrostatics(L, B, T, KG)["gm_t"]) < 0.01
    r = js.simulate(scene, duration=10.0)
    assert r.status == "ok" and np.abs(np.asarray(r.vessel.roll_pitch_yaw)[:, 0]).max() > 1e-3


@pytest.mark.parametrize("target", ["folder", "scene"])
def test_hydro_output_is_checked_before_the_solve(tmp_path, capsys, target):
    p = tmp_path / "box.toml"
    p.write_text((DATA / "box_20x10x2.toml").read_text())
    out = tmp_path if target == "folder" else p
    assert main(["hydro", str(p), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: -o:") and err.count("\n") == 1, err
    assert p.read_text() == (DATA / "box_20x10x2.toml").read_text()


def test_capytaine_missing_is_an_input_error(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "capytaine", None)
    import importlib.util
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "capytaine" else real(name, *a))
    p = tmp_path / "s.toml"
    p.write_text((DATA / "box_20x10x2.toml").read_text() + "\n[vessel.hydrodynamics]\ncapytaine = true\n")
    assert main(["check", str(p)]) == 2
    err = capsys.readouterr().err
    assert "vessel.hydrodynamics.capytaine" in err and "pip install" in err and err.count("\n") == 1


# --------------------------------------------------------------------------------------------
# Scenes: keys, errors, effects


BAD = [
    ('[waves]\ntype = "swell"\namplitude = 1.0\nperiod = 8.0\n', "waves.type"),
    ('[waves]\ntype = "regular"\namplitude = 1.0\n', "waves.period"),
    ('[waves]\ntype = "regular"\namplitude = 1.0\nperiod = 8.0\nfrequency = 0.8\n', "waves.period"),
    ('[waves]\ntype = "regular"\namplitude = -1.0\nperiod = 8.0\n', "waves.amplitude"),
    ('[waves]\ntype = "regular"\namplitude = 1.0\nperiod = 8.0\nhs = 2.0\n', "waves.hs"),
    ('[waves]\ntype = "jonswap"\nhs = 2.0\n', "waves.tp"),
    ('[waves]\ntype = "jonswap"\nhs = 2.0\ntp = 8.0\ngamma = 0.5\n', "waves.gamma"),
    ('[waves]\ntype = "jonswap"\nhs = 2.0\ntp = 8.0\nfrequency_range = [2.0, 1.0]\n', "waves.frequency_range"),
    ('[waves]\ntype = "jonswap"\nhs = 2.0\ntp = 8.0\ncomponents = 0\n', "waves.components"),
    ('[waves]\ntype = "jonswap"\nhs = 2.0\ntp = 8.0\nseed = "x"\n', "waves.seed"),
    ('[waves]\ntype = "regular"\namplitude = 1.0\nperiod = 8.0\nwind = 3\n', "waves.wind"),
]


@pytest.mark.parametrize("text,key", BAD)
def test_bad_wave_keys_name_the_key(text, key):
    with pytest.raises(js.SceneError) as e:
        box_scene(waves="\n" + text, hydro=False)
    assert e.value.key == key, str(e.value)


BAD_HYDRO = [
    ("[vessel.hull]\nlength = 10.0\nbeam = 5.0\ndraft = 1.0\n", "vessel.hull.kg"),
    ("[vessel.hull]\nlength = -10.0\nbeam = 5.0\ndraft = 1.0\nkg = 1.0\n", "vessel.hull.length"),
    ('[vessel.hull]\ntype = "mesh"\nfile = "x.stl"\n', "vessel.hull.type"),
    ("[vessel.hydrodynamics]\nfrequencies = [0.5, 1.0, 1.5, 2.0]\nadded_mass = [[1, 1, 1, 1, 1, 1]]\n"
     "damping = [[1, 1, 1, 1, 1, 1]]\n", "vessel.hydrodynamics.added_mass"),
    ("[vessel.hydrodynamics]\nfrequencies = [0.5, 1.0, 0.8, 2.0]\n", "vessel.hydrodynamics.frequencies"),
    ("[vessel.hydrodynamics]\nfrequencies = [0.5, 1.0, 1.5, 2.0]\nadded_mass = " + str([[1.0] * 6] * 4) + "\n",
     "vessel.hydrodynamics.damping"),
    ("[vessel.hydrodynamics]\nfrequencies = [0.5, 1.0, 1.5, 2.0]\nadded_mass = " + str([[1.0] * 6] * 4) +
     "\ndamping = " + str([[-1.0] * 6] * 4) + "\n", "vessel.hydrodynamics.damping"),
    ("[vessel.hydrodynamics]\nviscous_damping = [1, 2, 3]\n", "vessel.hydrodynamics.viscous_damping"),
    ("[vessel.hydrodynamics]\nviscous_damping = [0, 0, 0, -1, 0, 0]\n", "vessel.hydrodynamics.viscous_damping"),
    ("[vessel.hydrodynamics]\ncapytaine = 1\n", "vessel.hydrodynamics.capytaine"),
    ("[vessel.hydrodynamics]\n", "vessel.hydrodynamics"),
    ("[vessel.hydrodynamics]\nfrequencies = [0.5, 1.0, 1.5, 2.0]\nexcitation_amplitude = " + str([[1.0] * 6] * 4)
     + "\nexcitation_phase = " + str([[0.0] * 6] * 4) + "\n", "vessel.hydrodynamics.headings"),
]


@pytest.mark.parametrize("text,key", BAD_HYDRO)
def test_bad_hull_and_hydrodynamics_keys_name_the_key(text, key):
    base = box_scene(hydro=False).text.split("[vessel.hull]")[0]
    with pytest.raises(js.SceneError) as e:
        js.load_scene(base + text)
    assert e.value.key == key, str(e.value)


def test_waves_need_a_source_and_a_heading_in_the_tables(tmp_path, capsys):
    base = box_scene(hydro=False).text.split("[vessel.hull]")[0]
    with pytest.raises(js.SceneError) as e:
        js.load_scene(base + regular(1.0))
    assert e.value.key == "waves"
    with pytest.raises(js.SceneError) as e:
        box_scene(regular(1.0, heading=2.5))        # the tables hold 0 to pi/2
    assert e.value.key == "waves.heading"
    with pytest.raises(js.SceneError) as e:
        box_scene(regular(3.0))                     # beyond the tables' 2.0 rad/s
    assert e.value.key == "waves.frequency"
    p = tmp_path / "s.toml"
    p.write_text(base + '[waves]\ntype = "regular"\namplitude = 1.0\nperiod = "8"\n')
    assert main(["check", str(p)]) == 2
    assert capsys.readouterr().err.startswith("error: waves.period:")


def test_box_hull_gives_the_closed_form_hydrostatics():
    scene = box_scene(hydro=False)
    h = scene.vessel.hydrostatics
    ref = box_hydrostatics(L, B, T, KG)
    assert (h.waterplane_area, h.displaced_volume) == (ref["waterplane_area"], ref["displaced_volume"])
    assert h.gm_t == pytest.approx(T / 2 + B * B / (12 * T) - KG) and h.gm_l == pytest.approx(ref["gm_l"])
    assert not scene.warnings


def _terms(system):
    return {type(t).__name__: t for t in system.terms}


def test_effects_switch_waves_and_radiation_off_and_check_lists_them(tmp_path, capsys):
    scene = box_scene(regular(0.9), extra_hydro="viscous_damping = [0, 0, 0, 1e5, 0, 0]\n")
    p = tmp_path / "s.toml"
    p.write_text(scene.text)
    assert main(["check", str(p)]) == 0
    out = capsys.readouterr().out
    assert "waves: regular" in out and "radiation:" in out and "viscous damping" in out
    b = build(scene)
    assert "RadiationMemory" in _terms(b.system) and "WaveExcitation" in _terms(b.system)
    off = js.load_scene(scene.text + "\n[effects]\nwaves = false\nradiation = false\n")
    sea = {"WaveExcitation", "AddedMass", "LinearDamping", "RadiationMemory"}
    assert not sea & set(_terms(build(off).system))
    p.write_text(off.text)
    assert main(["check", str(p)]) == 0
    out = capsys.readouterr().out
    assert "waves, radiation" in out.split("switched off")[1] and "- waves:" not in out
    # nothing of the memory is traced when it is off: the step's arrays are those of the rigid body
    only_waves = js.load_scene(scene.text + "\n[effects]\nradiation = false\n")
    bs = build(only_waves)
    assert "RadiationMemory" not in _terms(bs.system) and "AddedMass" not in _terms(bs.system)
    solver = make_solver(bs.system, 0.05, make_scheme("newmark"), 1e-10, 25)
    s0, _ = initial_state(bs.system, solver, bs.c0, bs.v0)
    assert all(z.size == 0 for z in s0.z)       # no term carries integrator states
    jaxpr = jax.make_jaxpr(lambda s: step(bs.system, solver, s))(s0)
    n_exc = _terms(bs.system)["WaveExcitation"].excitation.omega.shape[0]
    big = [v.aval.shape for e in jaxpr.jaxpr.eqns for v in e.outvars if hasattr(v.aval, "shape") and v.aval.shape]
    assert max(max(s) for s in big) <= 6 + n_exc
    # with the memory: its states are carried in the State
    b = build(scene)
    solver = make_solver(b.system, 0.05, make_scheme("newmark"), 1e-10, 25)
    s0, _ = initial_state(b.system, solver, b.c0, b.v0)
    memory = _terms(b.system)["RadiationMemory"]
    assert [z.shape for z in s0.z if z.size] == [(memory.memory.p_re.shape[0], 2)]


# --------------------------------------------------------------------------------------------
# Gradients and batches through runs in waves


def test_gradient_through_a_run_in_waves_with_memory_agrees_with_finite_differences():
    """jax.grad (reverse mode) against central differences. The differences take their values from
    the same compiled program as the gradient (jax.value_and_grad), which spares a second
    compilation of the time loop (forward-only runs in waves are tested above)."""
    scene = box_scene(regular(1.0, ramp=5.0), duration=8.0, scheme="hht")

    def loss(gm, amp):
        r = js.simulate(scene, params={"vessel.hydrostatics.gm_t": gm, "waves.amplitude": amp})
        return jnp.sum(r.vessel.roll_pitch_yaw[:, 0] ** 2)

    value_and_grad = jax.jit(jax.value_and_grad(loss, argnums=(0, 1)))

    def value(gm, amp):
        return value_and_grad(gm, amp)[0]

    l0, g = value_and_grad(2.6, 0.2)
    h = 1e-4
    fd_gm = (value(2.6 + h, 0.2) - value(2.6 - h, 0.2)) / (2 * h)
    fd_a = (value(2.6, 0.2 + h) - value(2.6, 0.2 - h)) / (2 * h)
    assert abs(g[0] / fd_gm - 1) < 1e-5, (g[0], fd_gm)
    assert abs(g[1] / fd_a - 1) < 1e-5, (g[1], fd_a)
    assert abs(g[1] * 0.2 / l0 - 2) < 1e-3      # roll is linear in the wave amplitude


def test_batch_over_wave_heights_is_linear_in_the_height():
    scene = box_scene('\n[waves]\ntype = "jonswap"\nhs = 1.0\ntp = 7.0\nheading = 1.2\ncomponents = 30\nramp = 5.0\n',
                      duration=6.0)
    res, statuses = js.simulate_batch(scene, {"waves.hs": np.array([0.5, 1.0])})
    assert statuses == ["ok", "ok"]
    roll = np.asarray(res.vessel.roll_pitch_yaw)[:, :, 0]
    assert np.abs(roll[1]).max() > 1e-4
    np.testing.assert_allclose(roll[1], 2 * roll[0], atol=2e-3 * np.abs(roll[1]).max())
