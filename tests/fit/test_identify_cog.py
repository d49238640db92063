"""A mesh hull's COG by gradients: `identify --fit vessel.hull.cog` with the nonlinear hydrostatics
recovers the COG's height of a small flared prism (a closed mesh of 48 triangles, waterline at the
file's z = 0) from a noisy, damped roll decay released at 25 degrees, as tests/fit/test_identify_kg.py
does for the box's KG: the traced COG shifts the water plane over the mesh's fixed triangles."""
import json
import math
import warnings

import numpy as np
import pytest

import jaxslosh as js
from jaxslosh.fit.identify import identify
from jaxslosh.fit.problem import add_noise
from jaxslosh.hull.hydrostatics import rest_hydrostatics
from jaxslosh.hull.surface import prism_hull, write_hull_mesh

RHO = 1025.0
L, DRAFT = 20.0, 3.0
# the section (y, z), counter-clockwise: 8 m wide at the keel (z = -3), 11 m at the deck (z = 3)
SECTION = np.array([(-4.0, -DRAFT), (4.0, -DRAFT), (5.5, 3.0), (-5.5, 3.0)])
VOLUME = L * 0.5 * (8.0 + 9.5) * DRAFT            # 525 m^3 below the waterline
TRUE_COG = (0.0, 0.0, 0.6)                         # KG 3.6 m: GM_T 0.66 m
SCENE_COG = (0.0, 0.0, 0.5)                        # the fit's start: KG 2.8 % low
NOISE = {"roll": math.radians(0.2), "pitch": math.radians(0.2), "heave": 0.005}

SCENE = """
title = "flared prism roll decay"
[environment]
gravity = 9.81
water_density = 1025.0
[simulation]
duration = 16.0
dt = 0.1
scheme = "newmark"
[vessel]
mass = {mass}
inertia = [6.6e6, 2.2e7, 2.5e7]
[vessel.hull]
type = "mesh"
file = "{file}"
cog = [{cog}]
[vessel.hydrostatics]
model = "nonlinear"
[vessel.hydrodynamics]
viscous_damping = [0.0, 0.0, 0.0, 7.0e5, 0.0, 0.0]
[vessel.initial]
roll_pitch_yaw = [{roll}, 0.0, 0.0]
"""


def scene_text(path, cog):
    return SCENE.format(mass=RHO * VOLUME, file=path, cog=", ".join(map(repr, cog)), roll=math.radians(25.0))


@pytest.fixture(scope="module")
def decay(tmp_path_factory):
    d = tmp_path_factory.mktemp("cog")
    mesh = d / "prism.obj"
    write_hull_mesh(str(mesh), prism_hull(SECTION, L, nx=2, nz=2))
    path = d / "prism.toml"
    path.write_text(scene_text(mesh, SCENE_COG))
    clean = js.simulate(js.load_scene(scene_text(mesh, TRUE_COG)))
    assert clean.status == "ok"
    measured = add_noise(clean, NOISE, seed=5)
    data = d / "measured.h5"
    js.save_result(measured, data)
    return js.load_scene(str(path)), clean, measured, path, data, mesh


def test_the_mesh_is_small_and_the_decay_large(decay):
    scene, clean, _, _, _, _ = decay
    assert len(scene.vessel.hull.triangles()) == 48
    roll = np.asarray(clean.vessel.roll_pitch_yaw)[:, 0]
    # released at 25 degrees, it still rolls past 10 degrees in its last period
    assert np.max(np.abs(roll[-40:])) > math.radians(10.0)


def test_identify_recovers_the_cog_height_within_half_a_percent_of_kg(decay):
    """Weights 1 / noise, started 0.1 m low (KG 2.8 %): the height to 0.5 % of KG, the horizontal
    position to 1 cm (the record has neither heel nor trim), within five standard errors; the
    implied GM0 is the mesh's own about the fitted COG."""
    scene, _, measured, _, _, mesh = decay
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = identify(scene, measured, ["vessel.hull.cog"], weights={c: 1.0 / s for c, s in NOISE.items()})
    assert fit.converged, fit.message
    cog = np.asarray(fit.values["vessel.hull.cog"], dtype=float)
    se = np.asarray(fit.standard_errors["vessel.hull.cog"], dtype=float)
    kg = DRAFT + TRUE_COG[2]
    assert abs(cog[2] - TRUE_COG[2]) < 0.005 * kg, cog
    assert np.all(np.abs(cog[:2]) < 0.01), cog
    assert np.all(se > 0) and np.all(np.abs(cog - TRUE_COG) < 5 * se), (cog, se)
    assert se[2] < 0.002 * kg, se
    assert fit.quality == "" and fit.r2["roll"] > 0.99, (fit.quality, fit.r2)
    tris = prism_hull(SECTION, L, nx=2, nz=2) - cog
    own = rest_hydrostatics(tris, -cog[2], RHO, 9.81)
    assert fit.implied["vessel.hydrostatics.gm_t"] == pytest.approx(own["gm_t"], rel=1e-9)
    assert fit.implied_standard_errors["vessel.hydrostatics.gm_t"] == pytest.approx(se[2])


def test_cli_fits_the_cog_weighted_by_the_noise(decay, tmp_path, capsys):
    """`--noise roll=...,pitch=...,heave=...` weights the channels 1 / noise, as `weights` does."""
    from jaxslosh.cli import main
    _, _, _, path, data, _ = decay
    out = tmp_path / "fit.json"
    noise = ",".join(f"{c}={s!r}" for c, s in NOISE.items())
    code = main(["identify", str(path), "--data", str(data), "--fit", "vessel.hull.cog", "--noise", noise,
                 "-o", str(out)])
    printed = capsys.readouterr().out
    assert code == 0, printed
    fit = json.loads(out.read_text())
    assert fit["weights"] == pytest.approx({c: 1.0 / s for c, s in NOISE.items()}, rel=1e-12)
    cog, se = fit["values"]["vessel.hull.cog"], fit["standard_errors"]["vessel.hull.cog"]
    assert abs(cog[2] - TRUE_COG[2]) < 0.005 * (DRAFT + TRUE_COG[2]), cog
    assert 0 < se[2] < 0.002 * (DRAFT + TRUE_COG[2]), se
    assert any(s.startswith("vessel.hull.cog") for s in printed.splitlines()), printed


@pytest.mark.parametrize("args, named", [
    (["--noise", "roll=0"], "--noise: roll"),
    (["--noise", "roll"], "--noise"),
    (["--weights", "heave=-1"], "--weights: heave"),
    (["--noise", "roll=0.01", "--weights", "roll=3"], "--noise"),
    (["--noise", "sway=0.01"], "--noise: weights.sway"),
])
def test_cli_bad_noise_or_weights_exit_2_naming_the_flag(decay, tmp_path, capsys, args, named):
    from jaxslosh.cli import main
    _, _, _, path, data, _ = decay
    out = tmp_path / "fit.json"
    code = main(["identify", str(path), "--data", str(data), "--fit", "vessel.hull.cog", "-o", str(out)] + args)
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and named in err, err
    assert not out.exists()
