"""The liquid behind one interface (docs/design.md, "The liquid"): the models are the sub-packages of
jaxslosh/liquid, code elsewhere asks the AbstractLiquid contract and the tank's liquid form
(`Tank.form`: its `multimodal`, `face_normal`, `reduced`, `elastic`, ...) instead of which class or
string it holds, and the assembly's dispatch stays short. Read from the source with `ast`."""
import ast
import dataclasses
import inspect
import os

from jaxslosh.assemble.liquid import build_liquid_block
from jaxslosh.fem.mesh import ELEMENT_FORMS, FACE_FORMS
from jaxslosh.liquid.base import AbstractLiquid, NoLiquid
from jaxslosh.liquid.forms import FULL_ORDER
from jaxslosh.liquid.modal.term import ModalLiquid
from jaxslosh.scene.liquids import LiquidForm

ROOT = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "jaxslosh")
LIQUID = os.path.join(ROOT, "liquid")

#: the values of the tank keys that choose a liquid model, per attribute
CHOICES = {"model": {"fem", "multimodal"}, "element": set(ELEMENT_FORMS) | set(FACE_FORMS),
           "flow": {"2d", "3d"}, "expansion": {"exact", "third-order"}}
#: module-level tuples of such values (`t.fluid.element in FACE_FORMS`)
CHOICE_NAMES = {"FACE_FORMS", "ELEMENT_FORMS"}
#: modules whose string checks on these keys are still to go (their tanks' words and unknown counts,
#: reworked with the hull and wave variants this pass): the list only shrinks
PENDING: set = set()


def _sources():
    for dirpath, _, files in os.walk(ROOT):
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(dirpath, f)
                yield os.path.relpath(path, ROOT).replace(os.sep, "/"), path


def _liquid_classes() -> set:
    return {node.name for rel, path in _sources() if rel.startswith("liquid/")
            for node in ast.walk(ast.parse(open(path).read())) if isinstance(node, ast.ClassDef)}


def _named(node) -> set:
    if isinstance(node, ast.Name):
        return {node.id}
    if isinstance(node, ast.Attribute):
        return {node.attr}
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return set().union(*(_named(e) for e in node.elts)) if node.elts else set()
    return set()


def class_checks(source: str, classes: set) -> list:
    """(line, text) of each isinstance/issubclass on one of `classes`, and of `type(x) is C`."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ("isinstance", "issubclass") \
                and len(node.args) == 2 and _named(node.args[1]) & classes:
            out.append((node.lineno, ast.unparse(node)))
        if isinstance(node, ast.Compare) and any(isinstance(op, (ast.Is, ast.IsNot, ast.Eq, ast.NotEq)) for op in node.ops):
            sides = [node.left] + node.comparators
            if any(isinstance(s, ast.Call) and isinstance(s.func, ast.Name) and s.func.id == "type" for s in sides) \
                    and any(_named(s) & classes for s in sides):
                out.append((node.lineno, ast.unparse(node)))
    return out


def _choice_strings(node, attr) -> bool:
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value in CHOICES[attr]
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return any(_choice_strings(e, attr) for e in node.elts)
    return isinstance(node, ast.Name) and node.id in CHOICE_NAMES


def choice_checks(source: str) -> list:
    """(line, text) of each comparison of `x.model`, `x.element`, `x.flow` or `x.expansion` with one of
    its liquid values (a mooring line's `model == "catenary"` is not a liquid's)."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Compare):
            sides = [node.left] + node.comparators
            for s in sides:
                if isinstance(s, ast.Attribute) and s.attr in CHOICES and \
                        any(_choice_strings(o, s.attr) for o in sides if o is not s):
                    out.append((node.lineno, ast.unparse(node)))
                    break
    return out


def test_the_finders_see_the_forms():
    classes = {"FaceModel", "NoLiquid"}
    src = ("a = isinstance(m, FaceModel)\nb = isinstance(x, (int, liq.NoLiquid))\nc = type(x) is NoLiquid\n"
           "d = isinstance(x, int)\ne = issubclass(C, FaceModel)\n")
    assert [line for line, _ in class_checks(src, classes)] == [1, 2, 3, 5]
    src = ('a = t.model == "multimodal"\nb = t.fluid.element in FACE_FORMS\nc = t.flow != "3d"\n'
           'd = m.model == "catenary"\ne = t.expansion == "third-order"\nf = t.fluid.element in ("rt", "paper")\n'
           'g = args.name == "exact"\n')
    assert [line for line, _ in choice_checks(src)] == [1, 2, 3, 5, 6]


def test_no_isinstance_on_a_liquid_class_outside_the_liquid():
    """What differs between liquid models is a method or attribute of the AbstractLiquid contract
    (jaxslosh/liquid/base.py: `empty`, `step_inverse`, `static_start`, `staged_start`, ...) or is
    decided inside jaxslosh/liquid (forms.py, damping.sloshing_basis)."""
    classes = _liquid_classes()
    assert {"AbstractLiquid", "NoLiquid", "FaceModel", "MultimodalLiquid"} <= classes
    bad = [f"{rel}:{line}: {text}" for rel, path in sorted(_sources()) if not rel.startswith("liquid/")
           for line, text in class_checks(open(path).read(), classes)]
    assert not bad, "\n".join(bad)


def test_no_string_checks_on_the_liquid_model_outside_the_loader_and_the_liquid():
    """`model`, `fluid.element`, `flow` and `expansion` are read by the loader (jaxslosh/scene: the
    tank's `multimodal`, `face_normal`, `three_dimensional`, `third_order`) and the liquid itself."""
    found = {rel: choice_checks(open(path).read()) for rel, path in sorted(_sources())
             if not rel.startswith(("scene/", "liquid/"))}
    bad = [f"{rel}:{line}: {text}" for rel, hits in found.items() if rel not in PENDING for line, text in hits]
    assert not bad, "\n".join(bad)
    done = sorted(rel for rel in PENDING if not found.get(rel))
    assert not done, f"no string checks left in {done}: take them off PENDING"


#: the liquid form's answers that name which model a tank takes (scene/liquids.py)
KIND_FLAGS = {"multimodal", "face_normal"}


def kind_branches(source: str) -> list:
    """(line, text) of each read of a tank's (or its form's) `multimodal` or `face_normal`."""
    return [(node.lineno, ast.unparse(node)) for node in ast.walk(ast.parse(source))
            if isinstance(node, ast.Attribute) and node.attr in KIND_FLAGS]


def test_the_kind_finder_sees_the_flags():
    src = "a = t.multimodal\nb = t.form.face_normal\nc = t.form.reduced\nfrom ..liquid.multimodal import x\n"
    assert [line for line, _ in kind_branches(src)] == [1, 2]


def test_analysis_and_the_solver_ask_the_liquid_not_its_kind():
    """analysis/ and solve/ call one thing per question, the model behind the tank's form
    (liquid/forms.py `tank_liquid(t).sloshing_modes`, the AbstractLiquid contract), and never branch
    on which model a tank takes."""
    bad = [f"{rel}:{line}: {text}" for rel, path in sorted(_sources()) if rel.startswith(("analysis/", "solve/"))
           for line, text in kind_branches(open(path).read())]
    assert not bad, "\n".join(bad)


def test_every_form_has_its_liquid():
    """Each final liquid form of the loader (scene/liquids.py) maps to the final liquid that runs it."""
    assert set(FULL_ORDER) == set(LiquidForm.__subclasses__())
    assert all(issubclass(c, AbstractLiquid) and not getattr(c, "__abstractmethods__", None) for c in FULL_ORDER.values())


def test_the_liquid_block_dispatch_is_short():
    """Each model's builder lives in its sub-package; the assembly picks one (liquid/forms.py)."""
    n = len(inspect.getsource(build_liquid_block).splitlines())
    assert n < 40, f"build_liquid_block is {n} lines"


def test_no_private_imports_across_the_liquid_models():
    """A sub-package of jaxslosh/liquid imports another's public names only (`from ..face.element
    import _x` would tie one model to another's insides)."""
    bad = []
    for rel, path in _sources():
        if not rel.startswith("liquid/"):
            continue
        here = rel.split("/")[1] if rel.count("/") > 1 else ""
        for node in ast.walk(ast.parse(open(path).read())):
            if isinstance(node, ast.ImportFrom) and node.level > 0 and node.module:
                parts = rel.split("/")[:-1]
                base = parts[:len(parts) - (node.level - 1)] if node.level > 1 else parts
                target = base + node.module.split(".")
                there = target[1] if len(target) > 2 and target[0] == "liquid" else ""
                private = [a.name for a in node.names if a.name.startswith("_")]
                if private and there != here:
                    bad.append(f"{rel}:{node.lineno}: {private} from {'.'.join(target)}")
    assert not bad, "\n".join(bad)


#: the modules that describe a tank's liquid (`jaxslosh check`, the run's validity warnings) or
#: assemble the system: they ask the model behind the tank's form (`tank_liquid(t).describe_tank`)
#: or the block (`block.surfaces()`), never the form's flags
ASK_THE_LIQUID = ("assemble/about.py", "assemble/effects.py", "run/validity.py", "assemble/system.py")


def form_reads(source: str) -> list:
    """(line, text) of each read of a tank's liquid form (`t.form.x`), and of the tank's own
    answers that name the model (`t.multimodal`, `t.face_normal`)."""
    return sorted({(node.lineno, ast.unparse(node)) for node in ast.walk(ast.parse(source))
                   if isinstance(node, ast.Attribute) and (node.attr in KIND_FLAGS or (
                       isinstance(node.value, ast.Attribute) and node.value.attr == "form"))})


def test_the_form_finder_sees_the_reads():
    src = ("a = t.form.elastic\nb = t.multimodal\nc = tank.form\nd = x.formats.y\n"
           "e = scene.tanks[0].form.three_dimensional\n")
    assert [line for line, _ in form_reads(src)] == [1, 2, 5]


def test_the_check_words_and_the_assembly_ask_the_liquid_not_its_form():
    """A tank's words, its validity warnings and the system's assembly are one call for every
    model: no `t.form.<flag>` branch in these modules, and no multimodal path of their own."""
    bad = []
    for rel in ASK_THE_LIQUID:
        source = open(os.path.join(ROOT, rel)).read()
        bad += [f"{rel}:{line}: {text}" for line, text in form_reads(source)]
        bad += [f"{rel}:{node.lineno}: imports {node.module}" for node in ast.walk(ast.parse(source))
                if isinstance(node, ast.ImportFrom) and rel == "assemble/system.py"
                and (node.module or "").startswith("liquid.multimodal")]
    assert not bad, "\n".join(bad)


#: what the modules that ask the liquid (ASK_THE_LIQUID) still import of a model's package (its
#: thresholds): the watch's tables, its steepness cut included, are the liquid's answer
#: (AbstractLiquid.surface_table)
MODEL_IMPORTS = {("run/validity.py", "liquid.multimodal.steep"): {"DEFINITE_ON", "DEFINITE_SOFT", "STEEP_FULL",
                                                                 "STEEP_ON"}}


def test_the_modules_that_ask_the_liquid_import_no_model_but_its_thresholds():
    """The check words, the validity watch and the assembly import nothing of a model's package
    (liquid/<model>/...) but the thresholds listed in MODEL_IMPORTS (the list only shrinks)."""
    bad = []
    for rel in ASK_THE_LIQUID:
        for node in ast.walk(ast.parse(open(os.path.join(ROOT, rel)).read())):
            if isinstance(node, ast.ImportFrom) and node.level and (node.module or "").count(".") >= 2 \
                    and (node.module or "").startswith("liquid."):
                names = {a.name for a in node.names} - MODEL_IMPORTS.get((rel, node.module), set())
                if names:
                    bad.append(f"{rel}:{node.lineno}: {sorted(names)} from {node.module}")
    assert not bad, "\n".join(bad)


#: the contract's hooks that most models answer neutrally: each final liquid states its own
HOOKS = ("roundoff", "probe_modal", "surface_heave", "rigid_first_moment", "for_batch", "with_effects",
         "describe_tank", "surface_table")


def test_every_final_liquid_states_every_hook():
    """equinox's abstract-or-final: the hooks are abstract on AbstractLiquid, and each final liquid
    (NoLiquid and the reduced ModalLiquid too) defines each in its own body, none inherited."""
    assert set(HOOKS) <= AbstractLiquid.__abstractmethods__
    finals = {NoLiquid, ModalLiquid, *FULL_ORDER.values()}
    missing = [f"{c.__name__}.{h}" for c in sorted(finals, key=lambda c: c.__name__) for h in HOOKS
               if h not in vars(c)]
    assert not missing, missing


#: the liquid form's flags: which model a tank takes and how it runs (scene/liquids.py), read by the
#: loader and jaxslosh/liquid alone
FORM_FLAGS = {"multimodal", "face_normal", "reduced", "elastic", "three_dimensional", "third_order",
              "along_length_only", "element", "form", "name"}
#: what code elsewhere may ask a form: behaviour, named by what it answers
FORM_ASKS = {"dense_blocks", "dampable", "across_seas_warning", "carried_words"}


def flag_reads(source: str) -> list:
    """(line, text) of each read of a flag of a tank's liquid form (`t.form.elastic`)."""
    return sorted({(node.lineno, ast.unparse(node)) for node in ast.walk(ast.parse(source))
                   if isinstance(node, ast.Attribute) and node.attr in FORM_FLAGS
                   and isinstance(node.value, ast.Attribute) and node.value.attr == "form"})


def test_the_flag_finder_sees_the_flags():
    src = ("a = t.form.elastic\nb = t.form.dense_blocks\nc = tanks[0].form.reduced\nd = self.form\n"
           "e = t.form.along_length_only\nf = x.elastic\n")
    assert [line for line, _ in flag_reads(src)] == [1, 3, 5]


def test_every_form_answer_is_a_flag_or_a_behaviour():
    """A new answer of the forms is sorted here: a flag (which model, kept to the loader and the
    liquid) or a behaviour that code elsewhere may ask."""
    names = {n for c in (LiquidForm, *LiquidForm.__subclasses__()) for n in vars(c)
             if not n.startswith("_")} | {f.name for c in LiquidForm.__subclasses__() for f in dataclasses.fields(c)}
    assert names - FORM_FLAGS - FORM_ASKS == set()
    assert not FORM_FLAGS & FORM_ASKS


def test_no_branch_on_the_forms_flags_outside_the_loader_and_the_liquid():
    """Outside jaxslosh/scene and jaxslosh/liquid a tank's form is asked what it does (`dense_blocks`,
    `dampable`, `across_seas_warning`) or the liquid that runs it (liquid/forms.py `tank_liquid(t)`:
    `tank_unknowns`, `tank_bytes`, `sloshing_modes`, ...), never which model it is."""
    bad = [f"{rel}:{line}: {text}" for rel, path in sorted(_sources()) if not rel.startswith(("scene/", "liquid/"))
           for line, text in flag_reads(open(path).read())]
    assert not bad, "\n".join(bad)


#: the tank's own properties that read a flag of its form (scene/types.py Tank: `t.multimodal` is
#: `t.form.multimodal`), and the key tables whose presence makes a flag (`reduced`, `elastic`)
TANK_FLAGS = {"multimodal", "face_normal", "three_dimensional", "third_order", "along_length_only"}
FLAG_TABLES = {"reduction", "wall_spec"}
#: the multimodal package's own test of a scene's form (`multimodal_scene(scene)`)
FLAG_CALLS = {"multimodal_scene"}


def tank_flag_reads(source: str) -> list:
    """(line, text) of each read of a tank's form flag through the tank (`t.multimodal`,
    `tank.three_dimensional`), each test of a flag's key table (`t.reduction is not None`,
    `t.wall_spec is None`) and each call of a scene's form test (`multimodal_scene(own)`)."""
    out = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Attribute) and node.attr in TANK_FLAGS and isinstance(node.ctx, ast.Load):
            out.add((node.lineno, ast.unparse(node)))
        if isinstance(node, ast.Compare) and any(isinstance(op, (ast.Is, ast.IsNot)) for op in node.ops):
            sides = [node.left] + node.comparators
            if any(isinstance(s, ast.Attribute) and s.attr in FLAG_TABLES for s in sides) and \
                    any(isinstance(s, ast.Constant) and s.value is None for s in sides):
                out.add((node.lineno, ast.unparse(node)))
        if isinstance(node, ast.Call) and _named(node.func) & FLAG_CALLS:
            out.add((node.lineno, ast.unparse(node)))
    return sorted(out)


def test_the_tank_flag_finder_sees_the_reads():
    src = ("a = t.multimodal\nb = scene.tanks[0].three_dimensional\nc = t.reduction is not None\n"
           "d = t.wall_spec is None\ne = multimodal_scene(own)\nf = t.reduction.modes\ng = t.name\n"
           "h = build.multimodal_scene(s)\ni = t.fill_depth is None\n")
    assert [line for line, _ in tank_flag_reads(src)] == [1, 2, 3, 4, 5, 8]


def test_no_tank_flag_reads_outside_the_loader_and_the_liquid():
    """A tank is asked what its liquid does (its form's behaviour, the liquid that runs it, the
    block its builder makes), never which model it takes: outside jaxslosh/scene and jaxslosh/liquid
    no `t.multimodal` (or another flag the tank reads from its form), no test of the key tables that
    make the `reduced` and `elastic` flags, and no `multimodal_scene`."""
    bad = [f"{rel}:{line}: {text}" for rel, path in sorted(_sources()) if not rel.startswith(("scene/", "liquid/"))
           for line, text in tank_flag_reads(open(path).read())]
    assert not bad, "\n".join(bad)
