"""Fuzzed scenes through the command line, in process (SPEC section 2).

- Random valid scenes (small meshes, a few steps, random vessel particulars, tanks of plausible
  size, probes inside their tank) run to exit status 0, or fail cleanly with status 3 and a message;
  never a traceback.
- Random invalid scenes (one key of a valid scene given a bad value or type, an unknown key, a
  required key removed) exit with status 2 and one line on stderr that names the key.

Every distinct scene structure (mesh shapes, probe count, scheme, number of steps) costs a JAX
compilation of seconds, so the valid scenes draw their structure from a few templates and
randomise only the values.
"""
import math
import os
import tempfile

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import jaxslosh as js
from jaxslosh.cli import main

STEPS = 3
SETTINGS_VALID = settings(max_examples=6, deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
SETTINGS_INVALID = settings(max_examples=400, deadline=None, derandomize=True,
                            suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

# ------------------------------------------------------------------------------------------------
# TOML text from a nested dict (tables inline: one line per top-level key)

BARE = set("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-")


def _key(k):
    return k if k and set(k) <= BARE else '"' + k.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def to_toml(d):
    return "".join(f"{_key(k)} = {_value(v)}\n" for k, v in d.items())


# ------------------------------------------------------------------------------------------------
# Valid scenes

# (mesh of each tank, probes per tank, scheme table): the structure of a compiled run
TEMPLATES = [
    ((), 0, {"scheme": "hht", "alpha": 0.01}),
    (((3, 3, 2),), 2, {"scheme": "newmark"}),
    (((1, 1, 1), (2, 3, 1)), 1, {"scheme": "generalized-alpha", "rho_inf": 0.8}),
]
BASE = 1          # the template the invalid scenes start from: one tank with two probes

log_uniform = lambda lo, hi: st.floats(math.log(lo), math.log(hi)).map(math.exp)  # noqa: E731
vec3 = lambda lo, hi: st.lists(st.floats(lo, hi), min_size=3, max_size=3)  # noqa: E731


@st.composite
def probe_point(draw, size, fill):
    """A point the SPEC allows in a tank: in the liquid, on its surface, on the bottom or on a wall."""
    a, b, H = size
    where = draw(st.sampled_from(["inside", "surface", "bottom", "wall"]))
    x, y = draw(st.floats(0.0, a)), draw(st.floats(0.0, b))
    if where == "inside":
        return [x, y, draw(st.floats(0.0, fill))]
    if where == "surface":
        return [x, y, fill]
    if where == "bottom":
        return [x, y, 0.0]
    wall = draw(st.sampled_from(["x-", "x+", "y-", "y+"]))
    p = [x, y, draw(st.floats(0.0, H))]
    p["xy".index(wall[0])] = 0.0 if wall[1] == "-" else (a if wall[0] == "x" else b)
    return p


@st.composite
def valid_scene(draw, template=None):
    """A random valid scene as a dict; its structure from `template` (an index) or drawn."""
    k = draw(st.integers(0, len(TEMPLATES) - 1)) if template is None else template
    meshes, n_probes, scheme = TEMPLATES[k]
    dt = draw(log_uniform(1e-3, 0.1))
    rho_w = draw(st.floats(1000.0, 1030.0))
    mass = draw(log_uniform(1e4, 1e7))
    # principal moments from second moments of the mass along the axes (so I1 + I2 >= I3 holds)
    sxx, syy, szz = (mass * r * r for r in draw(vec3(0.3, 20.0)))
    inertia = [syy + szz, sxx + szz, sxx + syy]
    if draw(st.booleans()):           # a full symmetric matrix: the principal moments turned by a random rotation
        Q, _ = np.linalg.qr(np.asarray(draw(st.lists(st.floats(-1, 1), min_size=9, max_size=9))).reshape(3, 3)
                            + 3 * np.eye(3))
        I = Q @ np.diag(inertia) @ Q.T
        I = 0.5 * (I + I.T)
        inertia = [[float(I[i, j]) for j in range(3)] for i in range(3)]
    tanks, probes, liquid = [], [], 0.0
    for i, mesh in enumerate(meshes):
        size = draw(vec3(0.5, 10.0))
        fill = size[2] * draw(st.floats(0.05, 1.0))
        rho = draw(st.floats(500.0, 1500.0))
        tanks.append({"name": f"t{i}", "origin": [draw(st.floats(-10, 10)) - size[0] / 2,
                                                   draw(st.floats(-5, 5)) - size[1] / 2, draw(st.floats(-5, 2))],
                      "size": size, "fill_depth": fill, "mesh": list(mesh),
                      "fluid": {"density": rho, "sound_speed": draw(st.floats(300.0, 3000.0))}})
        liquid += rho * size[0] * size[1] * fill
        for j in range(n_probes):
            probes.append({"name": f"p{i}_{j}", "tank": f"t{i}", "point": draw(probe_point(size, fill))})
    volume = (mass + liquid) / rho_w * draw(st.sampled_from([1.0, 1.0, draw(st.floats(0.8, 1.2))]))
    scene = {
        "title": draw(st.text(st.characters(min_codepoint=32, max_codepoint=126), max_size=20)),
        "environment": {"gravity": draw(st.sampled_from([9.81, draw(st.floats(1.0, 20.0))])), "water_density": rho_w},
        "simulation": {"duration": STEPS * dt, "dt": dt, **scheme},
        "vessel": {
            "mass": mass, "inertia": inertia,
            "hydrostatics": {"waterplane_area": volume ** (2 / 3) * draw(st.floats(0.5, 3.0)),
                             "displaced_volume": volume, "gm_t": draw(st.floats(-0.5, 5.0)),
                             "gm_l": draw(st.floats(-0.5, 50.0))},
            "initial": {"position": draw(vec3(-0.5, 0.5)), "velocity": draw(vec3(-1.0, 1.0)),
                        "angular_velocity": draw(vec3(-2.0, 2.0)), "roll_pitch_yaw": draw(vec3(-1.0, 1.0))},
        },
    }
    if tanks:
        scene["tanks"] = tanks
    if probes:
        scene["probes"] = probes
    return scene


def _write(d, text):
    p = os.path.join(d, "scene.toml")
    with open(p, "w") as f:
        f.write(text)
    return p


def _errors(err):
    lines = [line for line in err.strip().splitlines() if line.strip()]
    return [line for line in lines if not line.startswith("warning:")]


@pytest.mark.parametrize("template", range(len(TEMPLATES)))
def test_valid_scenes_run_or_fail_cleanly(capsys, template):
    """Six random scenes of each structure (18 runs, 3 compilations)."""
    @SETTINGS_VALID
    @given(scene=valid_scene(template=template))
    def check(scene):
        _run_valid(capsys, scene)
    check()


def _run_valid(capsys, scene):
    capsys.readouterr()
    with tempfile.TemporaryDirectory() as d:
        path = _write(d, to_toml(scene))
        out = os.path.join(d, "out.h5")
        code = main(["run", path, "-o", out, "--no-progress"])
        io = capsys.readouterr()
        event(f"exit {code}")
        assert "Traceback" not in io.err
        assert code in (0, 3), (code, io.err)
        with h5py.File(out) as f:
            status = str(f.attrs["status"])
            k = int(f.attrs["steps_done"])
            n = f["time"].shape[0]
            for name in ("vessel/position", "vessel/quaternion", "energy/kinetic"):
                assert np.all(np.isfinite(f[name][:])), name
            q = f["vessel/quaternion"][:]
            assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
            for p in scene.get("probes", []):
                assert f[f"probes/{p['name']}/position"].shape == (n, 3)
        if code == 0:
            assert status == "ok" and k == STEPS and n == STEPS + 1
            assert "done" in io.out
            assert _errors(io.err) == [], io.err
        else:
            assert status != "ok" and k < STEPS and n == (k + 1 if "initial" not in status else 0), (status, k, n)
            errs = _errors(io.err)
            assert len(errs) == 1 and "numerical failure" in errs[0] and ("step" in errs[0] or "initial" in errs[0])


# ------------------------------------------------------------------------------------------------
# Invalid scenes: one mutation of a valid scene

NOT_A_NUMBER = ["abc", True, [1.0, 2.0], {"x": 1.0}]
NON_FINITE = [math.nan, math.inf, -math.inf]

# dotted path in the scene dict -> values that are certainly wrong there
BAD_VALUES = {
    "environment.gravity": [-1.0, -9.81] + NOT_A_NUMBER + NON_FINITE,
    "environment.water_density": [0.0, -1025.0] + NOT_A_NUMBER + NON_FINITE,
    "simulation.duration": [0.0, -1.0] + NOT_A_NUMBER + NON_FINITE,
    "simulation.dt": [0.0, -0.01, 1e9] + NOT_A_NUMBER + NON_FINITE,
    "simulation.scheme": ["rk4", "HHT", "", 3, True],
    "simulation.alpha": [-0.1, 0.5, 1.0] + NOT_A_NUMBER + NON_FINITE,
    "simulation.rho_inf": [-0.1, 1.5] + NOT_A_NUMBER,
    "simulation.save_every": [0, -1, 1.5, "1"],
    "simulation.tolerance": [0.0, -1e-10] + NOT_A_NUMBER,
    "simulation.max_iterations": [0, -3, 2.5],
    "simulation.substeps": [-1, 2.0],
    "vessel.mass": [0.0, -1.0] + NOT_A_NUMBER + NON_FINITE,
    "vessel.inertia": [[1.0, -1.0, 1.0], [0.0, 1.0, 1.0], [1.0, 1.0], "I", [[1.0, 2.0, 0.0], [0.0, 1.0, 0.0],
                                                                            [0.0, 0.0, 1.0]],
                       [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]], [1.0, math.nan, 1.0]],
    "vessel.hydrostatics.waterplane_area": [0.0, -200.0] + NOT_A_NUMBER + NON_FINITE,
    "vessel.hydrostatics.displaced_volume": [0.0, -400.0] + NOT_A_NUMBER,
    "vessel.hydrostatics.gm_t": NOT_A_NUMBER + NON_FINITE,
    "vessel.hydrostatics.gm_l": NOT_A_NUMBER + NON_FINITE,
    "vessel.hydrostatics.moment": ["exact", 1.0],
    "vessel.initial.position": [[0.0, 0.0], [0.0, "a", 0.0], 1.0, [0.0, math.nan, 0.0]],
    "vessel.initial.velocity": [[0.0, 0.0, 0.0, 0.0], "fast", [0.0, 0.0, math.inf]],
    "vessel.initial.angular_velocity": [[0.1], [True, 0.0, 0.0], {"x": 0.1}],
    "vessel.initial.roll_pitch_yaw": [[0.0, 0.0], [0.0, 0.0, "up"]],
    "tanks[0].name": ["", "a.b", "a[0]", 3],
    "tanks[0].origin": [[0.0, 0.0], "here", [0.0, 0.0, math.nan]],
    "tanks[0].size": [[0.0, 1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0], "big"],
    "tanks[0].fill_depth": [0.0, -1.0, 1e6] + NOT_A_NUMBER + NON_FINITE,
    "tanks[0].mesh": [[0, 1, 1], [1, 1, -2], [1.0, 1, 1], [1, 1], "fine"],
    "tanks[0].walls": ["steel", 3],
    "tanks[0].fluid.density": [0.0, -1000.0] + NOT_A_NUMBER + NON_FINITE,
    "tanks[0].fluid.sound_speed": [0.0, -1500.0] + NOT_A_NUMBER + NON_FINITE,
    "tanks[0].fluid.element": ["exact", 2],
    "probes[0].point": [[1e6, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 0.0], "A"],
    "probes[0].tank": ["no such tank", 0],
    "probes[0].name": ["", "a/b", 7],
    "title": [1, 2.5, True, ["t"]],
    "environment": [3, "earth"],
    "simulation": [1.0],
    "vessel": ["ship"],
    "tanks": [3, {"name": "t"}],
}
REQUIRED = ["simulation", "vessel", "simulation.duration", "simulation.dt", "vessel.mass", "vessel.inertia",
            "vessel.hydrostatics.waterplane_area", "vessel.hydrostatics.displaced_volume",
            "vessel.hydrostatics.gm_t", "vessel.hydrostatics.gm_l", "tanks[0].name", "tanks[0].origin",
            "tanks[0].size", "tanks[0].fill_depth", "tanks[0].mesh", "probes[0].name", "probes[0].point"]
# every key the loader knows, in any table (SPEC and README): an unknown key is none of these
KNOWN_KEYS = {
    "title", "environment", "simulation", "vessel", "tanks", "structures", "probes", "effects", "gravity",
    "water_density", "duration", "dt", "scheme", "alpha", "rho_inf", "save_every", "tolerance", "max_iterations",
    "chunk", "substeps", "mass", "inertia", "hydrostatics", "initial", "forced", "waterplane_area",
    "displaced_volume", "gm_t", "gm_l", "moment", "position", "velocity", "angular_velocity", "roll_pitch_yaw",
    "dof", "amplitude", "frequency", "ramp", "name", "origin", "size", "fill_depth", "mesh", "walls", "fluid",
    "density", "sound_speed", "element", "thickness", "material", "young", "poisson", "attach", "tank",
    "structure", "point", "buoyancy", "liquid", "coriolis", "centrifugal", "gravity_turning", "campaign", "limits",
    "headings", "seeds"}
TABLES = ["", "environment", "simulation", "vessel", "vessel.hydrostatics", "vessel.initial", "tanks[0]",
          "tanks[0].fluid", "probes[0]"]


def _parts(path):
    """'tanks[0].fluid.density' -> ['tanks', 0, 'fluid', 'density']."""
    out = []
    for p in path.split(".") if path else []:
        if "[" in p:
            name, idx = p[:-1].split("[")
            out += [name, int(idx)]
        else:
            out.append(p)
    return out


def _get_parent(d, path):
    parts = _parts(path)
    for p in parts[:-1]:
        d = d[p]
    return d, parts[-1]


def _has(d, path):
    try:
        for p in _parts(path):
            d = d[p]
        return True
    except (KeyError, IndexError, TypeError):
        return False


@st.composite
def invalid_scene(draw):
    """(scene dict with one thing wrong, the key the error must name)."""
    scene = draw(valid_scene(template=BASE))     # one tank with two probes: every table is there
    kind = draw(st.sampled_from(["value", "value", "value", "unknown", "missing", "duplicate"]))
    if kind == "value":
        path = draw(st.sampled_from(sorted(BAD_VALUES)))
        value = draw(st.sampled_from(BAD_VALUES[path]))
        parent, last = _get_parent(scene, path)
        parent[last] = value
        return scene, path
    if kind == "duplicate":
        scene["probes"][1]["name"] = scene["probes"][0]["name"]
        return scene, "probes[1].name"
    if kind == "unknown":
        table = draw(st.sampled_from(TABLES))
        name = draw(st.text(st.sampled_from("abcdefghijklmnopqrstuvwxyz_"), min_size=1, max_size=12))
        target = scene
        for p in _parts(table):
            target = target[p]
        if name in KNOWN_KEYS:
            name = name + "_bogus"
        target[name] = draw(st.sampled_from([1, 1.5, "x", True, [1, 2]]))
        return scene, (f"{table}.{name}" if table else name)
    path = draw(st.sampled_from(REQUIRED))
    parent, last = _get_parent(scene, path)
    del parent[last]
    return scene, path


def test_the_valid_base_of_the_invalid_scenes_loads():
    """The mutations below start from template BASE, which must load as it is (else they prove nothing)."""
    @settings(max_examples=50, deadline=None, derandomize=True)
    @given(valid_scene(template=BASE))
    def check(scene):
        js.load_scene(to_toml(scene))
    check()


@SETTINGS_INVALID
@given(case=invalid_scene(), command=st.sampled_from(["check", "check", "run"]))
def test_invalid_scenes_exit_2_with_one_line_naming_the_key(capsys, case, command):
    scene, key = case
    capsys.readouterr()
    with tempfile.TemporaryDirectory() as d:
        path = _write(d, to_toml(scene))
        out = os.path.join(d, "out.h5")
        args = ["check", path] if command == "check" else ["run", path, "-o", out, "--no-progress"]
        code = main(args)
        io = capsys.readouterr()
        event(f"{command}: {key.split('.')[0].split('[')[0]}")
        assert "Traceback" not in io.err
        errs = _errors(io.err)
        assert code == 2, (key, code, io.err)
        assert len(errs) == 1, (key, io.err)
        assert key in errs[0], (key, errs[0])
        assert not os.path.exists(out)
