"""One step path: solve/ sees only the System and its terms' hooks (physics/terms.py,
physics/unknowns.py). No structure-only step (no `_flex` name) and no branch on whether a System
has an optional piece of physics (`system.<attribute> is None`): flexible structures, radiation
memory and modal damping enter the step through the hooks of their terms. Read from the source
with `ast`."""
import ast
import os

ROOT = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "jaxslosh", "solve")
SYSTEM_NAMES = {"system", "sysm", "self.system"}


def _root(node):
    """The dotted name an attribute chain starts from (`system` for system.flex.bodies)."""
    while isinstance(node, ast.Attribute):
        node = node.value
    return node.id if isinstance(node, ast.Name) else None


def offences(source: str) -> list:
    """(line, what) for every `_flex` name and every `<system>.<attr> is [not] None` in the source."""
    out = []
    for node in ast.walk(ast.parse(source)):
        names = []
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.append(node.name)
        elif isinstance(node, ast.Name):
            names.append(node.id)
        elif isinstance(node, ast.Attribute):
            names.append(node.attr)
        out += [(node.lineno, f"name {n}") for n in names if "flex" in n.lower()]
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


def test_solve_has_one_step_path():
    bad = []
    for f in sorted(os.listdir(ROOT)):
        if f.endswith(".py"):
            with open(os.path.join(ROOT, f)) as fh:
                bad += [f"solve/{f}:{line}: {what}" for line, what in offences(fh.read())]
    assert not bad, "\n".join(bad)
