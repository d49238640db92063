"""One step path: solve/ sees only the System and its terms' hooks (physics/terms.py,
physics/unknowns.py). No structure-only step (no `_flex` name), no name of the prescribed motion
(`motion`, `prescribed`, `forced`) and no branch on whether a System has an optional piece of
physics (`system.<attribute> is None`): flexible structures, radiation memory, modal damping and
a prescribed motion enter the step through the hooks of their terms, and the System has no slot
for any of them. Read from the source with `ast`."""
import ast
import dataclasses
import os

from jaxslosh.physics.system import System

ROOT = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "jaxslosh", "solve")
SYSTEM_NAMES = {"system", "sysm", "self.system"}
#: the optional physics whose names solve/ must not hold: the structures and the prescribed motion
OPTIONAL = ("flex", "motion", "prescrib", "forced")


def _root(node):
    """The dotted name an attribute chain starts from (`system` for system.flex.bodies)."""
    while isinstance(node, ast.Attribute):
        node = node.value
    return node.id if isinstance(node, ast.Name) else None


def offences(source: str) -> list:
    """(line, what) for every name of optional physics (OPTIONAL: `_flex_step`, `system.motion`,
    `prescribed`, ...) and every `<system>.<attr> is [not] None` in the source (prose, as in
    "equations of motion", is no name)."""
    out = []
    for node in ast.walk(ast.parse(source)):
        names = []
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.append(node.name)
        elif isinstance(node, ast.Name):
            names.append(node.id)
        elif isinstance(node, ast.Attribute):
            names.append(node.attr)
        elif isinstance(node, ast.arg):
            names.append(node.arg)
        out += [(node.lineno, f"name {n}") for n in names if any(w in n.lower() for w in OPTIONAL)]
        if isinstance(node, ast.Compare) and any(isinstance(op, (ast.Is, ast.IsNot)) for op in node.ops):
            sides = [node.left] + list(node.comparators)
            none = any(isinstance(x, ast.Constant) and x.value is None for x in sides)
            on_system = [x for x in sides if isinstance(x, ast.Attribute) and _root(x) in SYSTEM_NAMES]
            if none and on_system:
                out.append((node.lineno, f"branch on {ast.unparse(on_system[0])} is None"))
    return out


def test_the_detector_finds_a_structure_step_and_an_optional_branch():
    src = ("def _flex_step(system, s):\n    return s\n\n"
           "def step(system, s):\n    if system.memory is None:\n        return s\n"
           "    if system.flex.bodies is not None:\n        return _flex_step(system, s)\n    return s\n")
    found = offences(src)
    assert (1, "name _flex_step") in found
    assert (5, "branch on system.memory is None") in found
    assert (7, "branch on system.flex.bodies is None") in found
    # an argument's default or a solver option is not optional physics
    assert offences("def f(system, alg0=None, n=None):\n    return alg0 is None or n is None\n") == []
    # the prescribed motion, read from the System or passed along, is found; prose is not
    src = ('def step(system, s, prescribed):\n    """The equations of motion."""\n'
           "    return system.motion.rigid_rows(s)\n")
    found = offences(src)
    assert (1, "name prescribed") in found and (3, "name motion") in found and len(found) == 2


def test_solve_has_one_step_path():
    bad = []
    for f in sorted(os.listdir(ROOT)):
        if f.endswith(".py"):
            with open(os.path.join(ROOT, f)) as fh:
                bad += [f"solve/{f}:{line}: {what}" for line, what in offences(fh.read())]
    assert not bad, "\n".join(bad)


def test_the_system_has_no_slot_for_optional_physics():
    """A prescribed motion is a term (physics/vessel.py AbstractPrescribedMotion, found by
    `System.prescribing`), not a field of the System: a scene without one has no such term."""
    fields = {f.name for f in dataclasses.fields(System)}
    assert not {n for n in fields if any(w in n.lower() for w in OPTIONAL)}, fields
    assert not hasattr(System, "motion")
