"""Every scene in scenes/ runs after the README's quick-start install (`pip install -e .`, no extras):
`jaxslosh check` passes on each, and every third-party module that checking them imports belongs to
a core dependency of pyproject.toml (or to one of theirs). A mesh hull once needed meshio, an extra:
`check scenes/parametric_roll.toml` then failed with ModuleNotFoundError on a plain install."""
import json
import os
import re
import subprocess
import sys
from importlib import metadata

import pytest

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib

from packaging.markers import default_environment
from packaging.requirements import Requirement

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENES = sorted(f for f in os.listdir(os.path.join(ROOT, "scenes")) if f.endswith(".toml"))

# one process checks every scene (JAX imported once), then says which top-level modules it holds
CHECK_ALL = r"""
import sys
before = set(sys.modules)          # the interpreter's start (site's .pth files: setuptools' hack)
import contextlib, io, json
from jaxslosh.cli.main import main
codes = {}
for s in sys.argv[1:]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        codes[s] = main(["check", "scenes/" + s, "--force"])
print(json.dumps({"codes": codes, "modules": sorted({m.split(".")[0] for m in set(sys.modules) - before})}))
"""


@pytest.fixture(scope="module")
def checked():
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    p = subprocess.run([sys.executable, "-c", CHECK_ALL, *SCENES], cwd=ROOT, env=env,
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout.strip().splitlines()[-1])


def test_every_scene_passes_check(checked):
    assert len(SCENES) >= 10
    assert checked["codes"] == {s: 0 for s in SCENES}


def _name(n):
    return re.sub(r"[-_.]+", "-", n).lower()


def core_closure():
    """The distributions a plain `pip install -e .` installs: the core dependencies of pyproject.toml
    (no extras) and, transitively, theirs (as this environment's metadata lists them)."""
    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as f:
        project = tomllib.load(f)["project"]
    # each requirement with the extras its requirer asks for (the core's "dask[distributed]")
    todo = [(Requirement(r), "") for r in project["dependencies"]]
    seen = set()
    while todo:
        r, extra = todo.pop()
        if r.marker is not None and not r.marker.evaluate(dict(default_environment(), extra=extra)):
            continue
        n = (_name(r.name), tuple(sorted(r.extras)))
        if n in seen:
            continue
        seen.add(n)
        try:
            reqs = [Requirement(x) for x in (metadata.requires(r.name) or [])]
        except metadata.PackageNotFoundError:
            continue                    # a dependency for another platform or Python
        todo += [(x, e) for x in reqs for e in ("", *r.extras)]
    return {name for name, _ in seen}


#: modules imported when present and passed over when not (an ImportError caught by their importer)
OPTIONAL = {
    "charset_normalizer": "numpy.f2py's crackfortran (through SciPy's array API compat) tries it",
}


def test_core_dependencies_cover_what_the_scenes_import(checked):
    installed = core_closure()
    assert "meshio" in installed          # the mesh hull of scenes/parametric_roll.toml
    dists = metadata.packages_distributions()
    missing = {}
    for m in checked["modules"]:
        if m in sys.stdlib_module_names or m not in dists or m == "jaxslosh" or m in OPTIONAL:
            continue
        names = {_name(d) for d in dists[m]}
        if not names & installed:
            missing[m] = sorted(names)
    assert not missing, f"modules the shipped scenes import, from no core dependency: {missing}"
