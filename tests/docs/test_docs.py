"""The documentation site's generated pages (docs/hooks.py) against the code they describe: the
scene reference names every key the loader accepts (and no key it refuses), the command reference
every command and option of the parser, the API page every public name; the README stays a front
page. Fast: the generators are called directly, mkdocs is not run (`.ci/run` builds the site
with --strict)."""
import argparse
import glob
import importlib
import importlib.util
import os
import re

import pytest

from jaxslosh.scene import fields, load
from jaxslosh.scene.keydocs import KEYS, TABLES
from jaxslosh.scene.types import SceneError

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _hooks():
    spec = importlib.util.spec_from_file_location("docs_hooks", os.path.join(ROOT, "docs", "hooks.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


hooks = _hooks()

_BASE = open(os.path.join(ROOT, "scenes", "vessel_only.toml")).read()
_TANK = """
[[tanks]]
name = "t"
origin = [-2.5, -2.5, -1.0]
size = [5.0, 5.0, 4.0]
fill_depth = 2.0
mesh = [4, 2, 2]
"""
# scenes that reach the tables the repository's scene files leave out (each table's spec holds
# all its keys, so one visit of a table is enough; a scene refused later still visited them)
_EXTRA = [
    _BASE + '[vessel.forced]\ndof = "roll"\namplitude = 0.01\nfrequency = 1.0\n',
    _BASE + _TANK + '[[tanks.baffles]]\nnormal = "x"\nposition = 2.5\nfrom = "bottom"\nheight = 1.0\n',
    _BASE + _TANK.replace('name = "t"', 'name = "t"\nshape = "prismatic"\nchamfers = { bottom = [0.5, 0.5] }'),
    _BASE + _TANK + '[tanks.reduction]\nmodes = 4\n[tanks.damping]\nratio = 0.01\n'
            '[[probes]]\nname = "B"\ntank = "t"\npoint = [4.0, 2.5, 2.0]\n'
            '[waves]\ntype = "jonswap"\nhs = 1.0\ntp = 8.0\n'
            '[campaign]\nseeds = 2\n[campaign.limits]\nroll = 0.1\n"probe.B" = 0.5\n',
    _BASE + '[[bodies]]\nname = "b"\nposition = [0.0, 100.0]\nmass = 1.0e5\ninertia = [1.0e6, 1.0e6, 1.0e6]\n'
            '[bodies.hull]\nlength = 10.0\nbeam = 5.0\ndraft = 2.0\nkg = 1.0\n[bodies.hydrostatics]\nmodel = "linear"\n',
]


def _accepted_keys() -> set:
    """Every key the loader's field specs name, recorded while it reads the repository's scenes
    and the scenes above, without indices (`tanks.fluid.density`)."""
    seen: dict = {}
    original = fields.read

    def spy(table, where, spec, required=()):
        where = re.sub(r"\[\d+\]", "", where)
        for key, (kind, _) in spec.items():
            seen[(where + "." if where else "") + key] = kind
        return original(table, where, spec, required)

    # every scene module that reads tables with fields.read (its own binding of the name)
    import importlib
    import pkgutil
    import jaxslosh.scene as scene_pkg
    modules = [m for m in (importlib.import_module(f"jaxslosh.scene.{i.name}")
                           for i in pkgutil.iter_modules(scene_pkg.__path__)) if getattr(m, "read", None) is original]
    saved = [m.read for m in modules]
    try:
        for m in modules:
            m.read = spy
        texts = [open(f).read() for f in sorted(glob.glob(os.path.join(ROOT, "scenes", "*.toml")))] + _EXTRA
        for text in texts:
            try:
                load.load_scene(text if text.endswith("\n") else text + "\n")
            except SceneError:
                pass
    finally:
        for m, r in zip(modules, saved):
            m.read = r
    keys = set()
    for key, kind in seen.items():
        if key.startswith("campaign.limits."):
            key = "campaign.limits.<channel>"
        if kind not in ("table", "tables"):
            keys.add(key)
    return keys


def test_scene_reference_names_every_key_the_loader_accepts():
    accepted = _accepted_keys()
    documented = {k for k, *_ in KEYS}
    assert len(accepted) > 100        # the spy saw the loader's tables
    assert sorted(accepted - documented) == [], "keys the loader accepts that the reference lacks"
    assert sorted(documented - accepted) == [], "keys the reference names that the loader refuses"
    page = hooks.scene_reference()
    for key in accepted:
        assert f"`{key}`" in page, key


def test_scene_reference_rows_are_complete():
    tables = {t for t, _ in TABLES}
    for key, default, unit, meaning in KEYS:
        assert default and meaning.strip(), key
        assert hooks._table_of(key, tables) in tables
    page = hooks.scene_reference()
    # the traceable keys are marked, one of each kind at least
    assert "`vessel.hydrostatics.gm_t` *traced*" in page
    assert "`tanks.damping.ratio` *traced*" in page
    assert "`simulation.dt` *traced*" not in page


def _subcommands():
    from jaxslosh.cli.common import COMMANDS
    return list(COMMANDS)


def test_command_reference_names_every_command_and_option():
    page = hooks.command_reference()
    names = hooks.command_names()
    assert names and set(names) == set(_subcommands())
    for name in names:
        assert f"## `{name}`" in page, name
        sub = hooks._subparser(name)
        for action in sub._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            for option in action.option_strings:
                assert option in page, (name, option)


def test_api_reference_names_every_public_name():
    import jaxslosh
    page = hooks.api_reference()
    api = hooks.public_api()
    assert set(api) == set(jaxslosh.__all__) - {"__version__"}
    for name, path in api.items():
        module, _, attr = path.rpartition(".")
        assert getattr(importlib.import_module(module), attr) is not None
        assert f"::: {path}" in page


def test_readme_is_a_front_page():
    text = open(os.path.join(ROOT, "README.md")).read()
    assert len(text.splitlines()) <= 150
    # the quick start's two commands, exactly (CI and users run them)
    assert ("python3 -m venv .venv && .venv/bin/pip install -q -e . && .venv/bin/jaxslosh run "
            "scenes/paper_ship_tank.toml -o paper_ship_tank.h5 && .venv/bin/jaxslosh plot paper_ship_tank.h5 "
            "-o paper_ship_tank.png") in text
    assert 'python3 -m venv .venv && .venv/bin/pip install -q -e ".[test]" && .venv/bin/python -m pytest' in text


def _pages():
    return [p for p in glob.glob(os.path.join(ROOT, "docs", "**", "*.md"), recursive=True)
            if "notebooks" not in p] + [os.path.join(ROOT, "README.md")]


@pytest.mark.parametrize("pattern, what", [
    (r"\b20\d\d-\d\d-\d\d\b", "a date"),
    (r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}\b", "a commit hash"),
    (r"[Mm]easured on \d|this session|last session|tonight|this morning", "work history"),
])
def test_pages_hold_no_history(pattern, what):
    for path in _pages():
        for n, line in enumerate(open(path), 1):
            assert not re.search(pattern, line), f"{os.path.relpath(path, ROOT)}:{n}: {what}: {line.strip()}"


def test_nav_pages_exist():
    text = open(os.path.join(ROOT, "mkdocs.yml")).read()
    generated = set(hooks.GENERATED)
    for page in re.findall(r"^\s*-\s*(?:[^:\n]+:\s*)?([\w./-]+\.(?:md|ipynb))\s*$", text, re.M):
        assert page in generated or os.path.exists(os.path.join(ROOT, "docs", page)), page
