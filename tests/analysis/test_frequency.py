"""The frequency domain (issue 20): the scene's residual linearised about rest by JAX, RAOs of the
hull alone against the classical 6-dof solution and Capytaine's own RAO post-processing, of the
paper ship with its tank against the time domain in regular waves, the linearisation's matrices
against the energies, reduced and elastic liquids, structures with multipliers, the RAO file and
command."""
import math
import sys
from pathlib import Path

import h5py
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.analysis.coupled import coupled_modes
from jaxslosh.analysis.linear import linearise
from jaxslosh.cli import main
from jaxslosh.hydro.box import box_hydrostatics
from jaxslosh.hydro.capytaine import to_toml
from jaxslosh.hydro.radiation import linear_response, restoring_matrix, rigid_mass_matrix
from jaxslosh.hydro.tables import interpolate_excitation, scene_tables
from jaxslosh.io.rao import load_rao
from jaxslosh.physics.system import advance_config

from helpers import mast, multibody_vessel

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parents[1] / "data"
RHO, G = 1025.0, 9.81
L, B, T, KG = 20.0, 10.0, 2.0, 2.5
MASS, INERTIA = 4.1e5, (6.0e6, 1.6e7, 2.0e7)
BV = (0.0, 0.0, 0.0, 8.0e5, 0.0, 0.0)
HEADINGS = (0.0, 0.7853981634, 1.570796327)     # the headings of tests/data/box_20x10x2_hydro.toml


def box_text(hydro: str) -> str:
    return (f'title = "box barge"\n[environment]\ngravity = {G}\nwater_density = {RHO}\n'
            f'[simulation]\nduration = 1.0\ndt = 0.05\n[vessel]\nmass = {MASS}\ninertia = {list(INERTIA)}\n' + hydro)


def box_tables_scene() -> js.Scene:
    """The test box with its Capytaine tables (tests/data) and a viscous roll damping."""
    text = (DATA / "box_20x10x2_hydro.toml").read_text()
    text = text[text.index("[vessel.hydrostatics]"):]
    return js.load_scene(box_text(text.replace("[vessel.hydrodynamics]",
                                               f"[vessel.hydrodynamics]\nviscous_damping = {list(BV)}")))


# --------------------------------------------------------------------------------------------
# the hull alone


def test_hull_alone_rao_equals_the_classical_six_dof_solution():
    """[C - w^2 (M + A(w)) + i w (B(w) + B_v)] xi = F at the tables' frequencies, for each heading
    (hydro/radiation.py linear_response): the residual's mass, restoring and damping are the rigid
    body's, the box's and the viscous table's, so the two agree to round-off."""
    scene = box_tables_scene()
    t = scene_tables(scene.vessel.hydrodynamics)
    r = js.rao(scene, t.omega, HEADINGS)
    h = scene.vessel.hydrostatics
    C = restoring_matrix(RHO, G, h.waterplane_area, h.displaced_volume, h.gm_t, h.gm_l)
    M = rigid_mass_matrix(MASS, np.diag(INERTIA))
    for k, beta in enumerate(HEADINGS):
        F = interpolate_excitation(t, t.omega, beta)
        ref = linear_response(t.omega, M, C, t.added_mass, t.damping + np.diag(BV)[None], F)
        err = np.abs(r.vessel[:, k] - ref).max(axis=0) / np.abs(ref).max(axis=0)
        assert err.max() < 1e-9, (beta, err)
    # between tabulated frequencies the tables are interpolated linearly, as the excitation is
    w = 0.5 * (t.omega[3] + t.omega[4])
    r1 = js.rao(scene, [w], [HEADINGS[2]])
    A = 0.5 * (t.added_mass[3] + t.added_mass[4])
    Bd = 0.5 * (t.damping[3] + t.damping[4]) + np.diag(BV)
    ref = linear_response([w], M, C, A[None], Bd[None], interpolate_excitation(t, [w], HEADINGS[2]))
    assert np.abs(r1.vessel[0, 0] - ref[0]).max() < 1e-9 * np.abs(ref).max()


def test_hull_alone_rao_against_capytaine_post_processing():
    """Capytaine's own RAO (capytaine.post_pro.rao) of the same body and tables, with the scene's
    inertia, the box's hydrostatic stiffness and the viscous roll damping: within 0.5 % (its
    e^{-i w t} convention: our RAO is its complex conjugate)."""
    cpt = pytest.importorskip("capytaine")
    xr = pytest.importorskip("xarray")
    from jaxslosh.hydro.capytaine import _hull_body
    from jaxslosh.scene.types import BoxHull
    w = np.linspace(0.3, 1.8, 6)
    heads = [0.0, math.pi / 4, math.pi / 2]
    body = _hull_body(cpt, BoxHull(length=L, beam=B, draft=T, kg=KG), 2.0, omega_max=w.max())
    probs = [cpt.RadiationProblem(body=body, radiating_dof=d, omega=x, rho=RHO, g=G) for d in body.dofs for x in w]
    probs += [cpt.DiffractionProblem(body=body, wave_direction=b, omega=x, rho=RHO, g=G) for b in heads for x in w]
    ds = cpt.assemble_dataset(cpt.BEMSolver().solve_all(probs, progress_bar=False))
    dofs = list(body.dofs)
    hs = box_hydrostatics(L, B, T, KG)
    C = restoring_matrix(RHO, G, hs["waterplane_area"], hs["displaced_volume"], hs["gm_t"], hs["gm_l"])

    def da(a):
        return xr.DataArray(a, dims=["influenced_dof", "radiating_dof"],
                            coords={"influenced_dof": dofs, "radiating_dof": dofs})

    ds["inertia_matrix"] = da(rigid_mass_matrix(MASS, np.diag(INERTIA)))
    ds["hydrostatic_stiffness"] = da(C)
    ref = np.conj(cpt.post_pro.rao(ds, dissipation=da(np.diag(BV))).transpose(
        "omega", "wave_direction", "radiating_dof").values)
    # the same tables as a scene holds them
    A = ds["added_mass"].transpose("omega", "influenced_dof", "radiating_dof").values
    Bd = ds["radiation_damping"].transpose("omega", "influenced_dof", "radiating_dof").values
    F = np.conj(ds["excitation_force"].transpose("omega", "wave_direction", "influenced_dof").values)
    hydro = {"frequencies": w.tolist(), "added_mass": A.tolist(), "damping": Bd.tolist(), "viscous_damping": list(BV),
             "headings": heads, "excitation_amplitude": np.abs(F).tolist(), "excitation_phase": np.angle(F).tolist()}
    scene = js.load_scene(box_text(to_toml({"hydrostatics": hs, "hydrodynamics": hydro})))
    r = js.rao(scene, w, heads)
    err = np.abs(r.vessel - ref).max(axis=(0, 1)) / np.abs(ref).max(axis=(0, 1))
    print("relative difference per dof", err)
    assert err.max() < 0.005


# --------------------------------------------------------------------------------------------
# the linearisation of the paper example


HULL = "[vessel.hull]\nlength = 16.0\nbeam = 10.0\ndraft = 2.5\nkg = 2.9133333333333336\n\n"


def with_hull(text: str) -> js.Scene:
    """A scene with the paper ship's box hull (scenes/paper_ship_waves.toml): Froude-Krylov forces to
    excite it (its closed-form GM_L differs from the scene's table, which the restoring keeps)."""
    return js.load_scene(text.replace("[vessel.hydrostatics]", HULL + "[vessel.hydrostatics]", 1))


@pytest.fixture(scope="module")
def paper():
    scene = js.load_scene(ROOT / "scenes" / "paper_ship_tank.toml")
    return scene, linearise(scene)


def test_linearisation_is_the_hessian_of_the_energies(paper):
    """At rest the mass matrix is the Hessian of the kinetic energy in the velocities and the
    stiffness the Hessian of the potential along the step's increments (rotations on the group):
    the residual is Lagrangian (tests/physics/test_model.py), so its linearisation is symmetric too."""
    scene, lin = paper
    sysm, c0 = lin.built.system, lin.built.c0
    n = lin.n
    H_T = np.asarray(jax.jit(jax.hessian(lambda v: sysm.kinetic_energy(c0, v)))(jnp.zeros(n)))
    H_V = np.asarray(jax.jit(jax.hessian(lambda x: sysm.potential_energy(advance_config(c0, x))))(jnp.zeros(n)))
    assert np.abs(lin.M - H_T).max() < 1e-9 * np.abs(H_T).max()
    assert np.abs(lin.K - H_V).max() < 1e-9 * np.abs(H_V).max()
    assert np.abs(lin.K - lin.K.T).max() < 1e-12 * np.abs(lin.K).max()
    assert not lin.C.any()                        # no damping in the paper's scene
    # the vessel's rigid mass with the liquid's: 410 t in every translation
    assert np.allclose(np.diag(lin.M)[:3], 3.35e5 + 75.0 * 1000.0, rtol=1e-9)


def test_probe_on_the_tank_bottom_moves_with_the_hull(paper):
    """Probe A sits on the tank's bottom and follows the tank (SPEC section 1): its RAO is the rigid
    kinematics X + Theta x r of its point; probe B, on the free surface above it, adds the liquid's."""
    scene, lin = paper
    r = js.rao(with_hull(scene.text), np.linspace(0.5, 3.0, 11), [math.pi / 4], linearisation=lin)
    i = lin.probe_names.index("A")
    p = np.asarray(lin.built.probes.points)[i]
    rigid = r.vessel[:, 0, :3] + np.cross(r.vessel[:, 0, 3:], p)
    assert np.abs(r.probes["A"][:, 0] - rigid).max() < 1e-9 * np.abs(rigid).max()
    assert np.abs(r.probes["B"][:, 0] - rigid).max() > 0.1 * np.abs(rigid).max()


def test_reduced_liquid_gives_the_full_liquids_rao(paper):
    """The liquid on 20 modes with the static correction: the same RAOs as the full order within
    1 % of the peak, around the roll resonance and the first sloshing modes."""
    scene, lin = paper
    reduced = with_hull(scene.text.replace("[[probes]]", "[tanks.reduction]\nmodes = 20\n\n[[probes]]", 1))
    w = np.linspace(0.5, 3.0, 26)
    full = js.rao(with_hull(scene.text), w, [math.pi / 4], linearisation=lin)
    red = js.rao(reduced, w, [math.pi / 4])
    for name in ("roll", "B"):
        a = full.vessel[:, 0, 3] if name == "roll" else full.probes["B"][:, 0, 2]
        b = red.vessel[:, 0, 3] if name == "roll" else red.probes["B"][:, 0, 2]
        assert np.abs(a - b).max() < 0.01 * np.abs(a).max(), name


# --------------------------------------------------------------------------------------------
# the time domain against the frequency domain


def paper_regular_scene(omega, heading=math.pi / 4, amplitude=0.02, duration=300.0, dt=0.01, damping=True):
    """The paper ship with its tank (scenes/paper_ship_waves.toml) in a regular wave: its box hull's
    Capytaine tables to 3.2 rad/s (tests/data/paper_hull_hydro.toml: the first sloshing modes are at
    2.53 rad/s), Froude-Krylov excitation (any heading), the trapezoidal rule (no numerical damping).
    With `damping`, a 1 % liquid damping ([tanks.damping], SPEC section 5)."""
    text = (ROOT / "scenes" / "paper_ship_waves.toml").read_text()
    head = text[:text.index("[vessel.hydrodynamics]")]
    head = head.replace('scheme = "hht"', 'scheme = "newmark"').replace("alpha = 0.05\n", "") \
        .replace("duration = 600.0", f"duration = {duration!r}").replace("dt = 0.05", f"dt = {dt!r}") \
        .replace("save_every = 2", "save_every = 5")
    tab = (DATA / "paper_hull_hydro.toml").read_text()
    tab = tab[tab.index("[vessel.hydrodynamics]"):].replace(
        "[vessel.hydrodynamics]", '[vessel.hydrodynamics]\nviscous_damping = [0.0, 0.0, 0.0, 4.0e5, 0.0, 0.0]\n'
                                  'excitation = "froude-krylov"\n')
    waves = (f'\n[waves]\ntype = "regular"\namplitude = {amplitude!r}\nfrequency = {omega!r}\n'
             f'heading = {heading!r}\nramp = 30.0\n\n')
    tail = text[text.index("[[tanks]]"):]
    if damping:
        tail = tail.replace("[[probes]]", "[tanks.damping]\nratio = 0.01\n\n[[probes]]", 1)
    return js.load_scene(head + tab + waves + tail)


def steady_harmonic(t, x, w, modes, t0):
    """The part of x at the forcing frequency w, X with x = Re(X e^{i w t}), fitted by least squares
    with a mean and the free decay of every coupled mode (damped frequency and decay rate from
    coupled_modes): lightly damped modes (the sloshing ones, 0.5 % of critical here) are still
    ringing from the ramp when the window starts, and a plain fit of w alone mistakes them for the
    forced response by 2 % near them."""
    tt = t - t0
    cols = [np.cos(w * t), np.sin(w * t), np.ones_like(t)]
    for wd, z in zip(modes.damped, modes.damping_ratio):
        if abs(wd - w) > 1e-3:
            s = z * modes.omega[list(modes.damped).index(wd)]
            cols += [np.exp(-s * tt) * np.cos(wd * tt), np.exp(-s * tt) * np.sin(wd * tt)]
    c = np.linalg.lstsq(np.stack(cols, axis=1), x, rcond=None)[0]
    return complex(c[0], -c[1])


@pytest.mark.slow
def test_paper_ship_in_regular_waves_time_domain_against_rao():
    """Five regular waves of 2 cm from 45 degrees (roll, pitch and both sloshing directions
    excited): below the roll resonance, at it (0.93 rad/s, the coupled roll mode is 0.926), between,
    below the first sloshing modes and 2 % below them (2.48 rad/s; the coupled sloshing modes are
    2.532 and 2.533). After 100 s of the 300 s runs, the steady amplitudes of roll and of probe B's
    vertical displacement within 1 % of the RAO, the phases within 2 degrees."""
    freqs = [0.6, 0.93, 1.6, 2.2, 2.48]
    a = 0.02
    scene = paper_regular_scene(freqs[0], amplitude=a)
    lin = linearise(scene)
    r = js.rao(scene, freqs, [math.pi / 4], linearisation=lin)
    modes = coupled_modes(scene, 10, linearisation=lin)
    assert abs(modes.damped[list(modes.dominant).index("roll")] - 0.926) < 0.01
    worst = []
    for i, w in enumerate(freqs):
        res = js.simulate(paper_regular_scene(w, amplitude=a))
        assert res.status == "ok"
        t = np.asarray(res.time)
        keep = t > 100.0
        for name, x, ref in [("roll", np.asarray(res.vessel.roll_pitch_yaw)[keep, 0], r.vessel[i, 0, 3]),
                             ("B", np.asarray(res.probes["B"].displacement)[keep, 2], r.probes["B"][i, 0, 2])]:
            X = steady_harmonic(t[keep], x, w, modes, 100.0) / a
            ratio, phase = abs(X) / abs(ref), math.degrees(np.angle(X / ref))
            print(f"w = {w} rad/s {name}: time / frequency domain amplitude {ratio:.5f}, phase {phase:+.3f} deg "
                  f"(RAO {abs(ref):.4g})")
            worst.append((abs(ratio - 1), abs(phase)))
            assert abs(ratio - 1) < 0.01 and abs(phase) < 2.0, (w, name, ratio, phase)
    print("largest amplitude error {:.3%}, phase {:.3f} deg".format(*np.max(worst, axis=0)))


# --------------------------------------------------------------------------------------------
# structures and elastic walls


def test_vessel_with_a_stiff_mast_linearises_with_its_multipliers():
    """A very stiff mast in its own frame tied by multipliers (E = 2.1e15 Pa): the interface rows
    carry no inertia, the coupled roll mode is the rigid ship's sqrt(rho g V GM_T / I_xx) within
    1e-4 (the scene's inertia is the whole ship's, mast included), and the mast's tip probe moves
    with the ship: X + Theta x r."""
    m = 3.25e5
    text = multibody_vessel(mass=m) + mast(mesh=(1, 1, 4), young=2.1e15) + \
        '[[probes]]\nname = "tip"\nstructure = "mast"\npoint = [0.15, 0.15, 4.0]\n'
    scene = js.load_scene(text)
    lin = linearise(scene)
    assert not lin.dynamic.all() and not lin.M[:, ~lin.dynamic].any()
    modes = coupled_modes(scene, 4, linearisation=lin)
    w_ref = math.sqrt(RHO * G * (m / RHO) * 1.67 / 4.9e6)
    roll = modes.omega[list(modes.dominant).index("roll")]
    assert abs(roll / w_ref - 1) < 1e-4, (roll, w_ref)
    P = lin.probes[0]                                    # (3, n): the tip's displacement per unit x
    tip = np.array([-0.15, -0.15, 1.0]) + np.array([0.15, 0.15, 4.0])
    # the static response to a roll moment, surge, sway and yaw held (nothing restores them): the mast
    # follows the ship rigidly, frames, multipliers and modes included
    F = np.zeros(lin.n)
    F[3] = 1.0e6
    keep = np.r_[2:5, 6:lin.n]
    u = np.zeros(lin.n)
    u[keep] = np.linalg.solve(lin.K[np.ix_(keep, keep)], F[keep])
    rigid = u[:3] + np.cross(u[3:6], tip)
    assert np.abs(P @ u - rigid).max() < 1e-6 * np.abs(rigid).max()


# slow, for the default suite's budget: it keeps the elastic walls' sloshing frequencies against the rigid
# tank's (tests/fem/test_elastic_tank.py)
@pytest.mark.slow
def test_elastic_tank_walls_leave_the_coupled_sloshing_mode():
    """The paper's tank with 5 cm steel walls (scenes/paper_ship_elastic_tank.toml): the coupled
    roll and first sloshing frequencies within 0.5 % of the rigid tank's."""
    rigid = coupled_modes(js.load_scene(ROOT / "scenes" / "paper_ship_tank.toml"), 6)
    elastic = coupled_modes(js.load_scene(ROOT / "scenes" / "paper_ship_elastic_tank.toml"), 6)
    for kind in ("roll", "liquid"):
        a = rigid.omega[list(rigid.dominant).index(kind)]
        b = elastic.omega[list(elastic.dominant).index(kind)]
        print(f"{kind}: rigid {a:.5f}, elastic walls {b:.5f} rad/s")
        assert abs(b / a - 1) < 0.005


# --------------------------------------------------------------------------------------------
# the file and the command


def test_rao_command_writes_the_spec_file_and_a_plot(tmp_path, capsys):
    scene = tmp_path / "box.toml"
    text = (DATA / "box_20x10x2_hydro.toml").read_text()
    scene.write_text(box_text(text[text.index("[vessel.hydrostatics]"):]) +
                     '[[tanks]]\nname = "t"\norigin = [-1.0, -1.0, -1.0]\nsize = [2.0, 2.0, 2.0]\nfill_depth = 1.0\n'
                     'mesh = [2, 2, 2]\n[[probes]]\nname = "s"\ntank = "t"\npoint = [2.0, 1.0, 1.0]\n')
    out, fig = tmp_path / "box_rao.h5", tmp_path / "rao.png"
    assert main(["rao", str(scene), "--frequencies", "0.2:2.0:10", "--headings", "0,1.570796327", "-o", str(out),
                 "--plot", str(fig)]) == 0
    assert "done: RAOs at 10 frequencies x 2 headings" in capsys.readouterr().out
    with h5py.File(out, "r") as f:
        assert f.attrs["format"] == "jaxslosh.rao" and f.attrs["format_version"] == 1
        assert "[vessel.hull]" not in f.attrs["scene"] and "[[tanks]]" in f.attrs["scene"]
        assert f["frequency"].shape == (10,) and f["heading"].shape == (2,)
        assert f["rao/vessel"].shape == (10, 2, 6) and f["rao/vessel"].dtype == np.complex128
        assert f["rao/probes/s"].shape == (10, 2, 3)
    d = load_rao(str(out))
    assert abs(abs(d.vessel[0, 0, 2]) - 1) < 0.1          # long waves: the hull heaves with the surface
    assert fig.stat().st_size > 10000
    # bad input: one line, exit 2
    for args, key in [(["--frequencies", "0.05:1:5"], "frequencies"), (["--frequencies", "1:2"], "--frequencies"),
                      (["--headings", "2.0"], "headings"), (["--headings", "a"], "--headings")]:
        assert main(["rao", str(scene), "-o", str(tmp_path / "x.h5")] + args) == 2
        err = capsys.readouterr().err
        assert key in err and err.count("\n") == 1, err
    # the RAO file is not overwritten by mistake: a file that is not ours is refused
    other = tmp_path / "other.h5"
    other.write_bytes(b"not hdf5")
    assert main(["rao", str(scene), "-o", str(other)]) == 2
    forced = tmp_path / "forced.toml"
    forced.write_text(scene.read_text().replace("[vessel.hydrostatics]", '[vessel.forced]\ndof = "roll"\n'
                                                "amplitude = 0.01\nfrequency = 1.0\n\n[vessel.hydrostatics]"))
    assert main(["rao", str(forced)]) == 2
    assert "vessel.forced" in capsys.readouterr().err


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-s"]))
