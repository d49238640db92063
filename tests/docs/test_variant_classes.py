"""Variants as classes (docs/design.md "Variants as classes, abstract or final"): each family is an
abstract class with one final class per value of its scene key and one registry the loader reads;
code outside the loader (jaxslosh/scene/) asks the instance and never compares the key's string."""
import ast
import dataclasses
import inspect
import os

import pytest

from jaxslosh.physics.vessel import RESTORING_FORMS, AbstractRestoring
from jaxslosh.scene.hull import MOMENTS
from jaxslosh.scene.hulls import HULLS, Hull
from jaxslosh.scene.seas import WAVES, Waves
from jaxslosh.solve.schemes import SCHEMES, AbstractScheme

from test_layout import string_constants

ROOT = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "jaxslosh")

#: attribute -> the strings that would be a branch on a variant: hulls' and waves' `type`, the
#: scheme's name and the restoring's moment form. Other `.type` comparisons stay legal (meshio's
#: cell blocks in fem/meshfile.py compare `c.type == "hexahedron"`, which is no scene variant).
VARIANT_STRINGS = {"type": set(HULLS) | set(WAVES), "scheme": set(SCHEMES), "moment": set(RESTORING_FORMS)}


def variant_branches(source: str) -> list:
    """(line, text) of each comparison of `x.type`, `x.scheme` or `x.moment` with a variant's name."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Compare):
            sides = [node.left] + node.comparators
            attrs = {s.attr for s in sides if isinstance(s, ast.Attribute) and s.attr in VARIANT_STRINGS}
            if any(string_constants(s) & VARIANT_STRINGS[a] for a in attrs for s in sides):
                out.append((node.lineno, ast.unparse(node)))
    return out


def test_variant_branches_are_found():
    src = ('a = hull.type == "box"\nb = w.type != "regular"\nc = sim.scheme in ("hht", "newmark")\n'
           'd = h.moment == "paper"\ne = c.type == "hexahedron"\nf = hull.kind == "box"\n')
    assert [line for line, _ in variant_branches(src)] == [1, 2, 3, 4]


def test_no_string_branches_on_variants_outside_the_loader():
    bad = []
    for dirpath, _, files in os.walk(ROOT):
        rel = os.path.relpath(dirpath, ROOT)
        if rel == "scene" or rel.startswith("scene" + os.sep):
            continue
        for f in sorted(files):
            if f.endswith(".py"):
                path = os.path.join(dirpath, f)
                bad += [f"{os.path.relpath(path, ROOT)}:{line}: {text}" for line, text in variant_branches(open(path).read())]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("registry, base, key", [(HULLS, Hull, "type"), (WAVES, Waves, "type"),
                                                  (SCHEMES, AbstractScheme, "name"),
                                                  (RESTORING_FORMS, AbstractRestoring, "form")])
def test_each_registry_holds_final_kinds_of_an_abstract_base(registry, base, key):
    assert inspect.isabstract(base), base
    for value, cls in registry.items():
        assert issubclass(cls, base) and not inspect.isabstract(cls), cls
        assert getattr(cls, "__final__", False), f"{cls.__name__} is not marked @final"
        own = next((f.default for f in dataclasses.fields(cls) if f.name == key), None) \
            if dataclasses.is_dataclass(cls) and key == "type" else getattr(cls, key)
        assert own == value, (cls, own, value)


def test_the_loader_checks_the_moment_forms_the_terms_have():
    """The loader sits below physics/ (it imports no JAX), so it lists the moment forms itself."""
    assert set(MOMENTS) == set(RESTORING_FORMS)
