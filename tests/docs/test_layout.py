"""The package's layout (docs/design.md): sub-packages in layers, imports at the top of files and
only downwards (the lazy `import_module` calls too), no private name imported from another
sub-package, no import circles, no module over 500 lines. Read from the source with `ast`.
`python -m tests.docs.layers --write` writes LAYERS into docs/design.md and jaxslosh/__init__.py."""
import ast
import os

import pytest

ROOT = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "jaxslosh")

# lowest first; a module may import its own package and the packages on earlier lines
LAYERS = [
    {"_version", "staging"},
    # the schemes' registry is read by the scene loader: plain classes, no JAX
    {"fem.mesh", "fem.meshfile", "fem.slip", "physics.kinematics", "solve.schemes"},
    {"fem.shapes"},
    {"hull"},
    # the tank shapes: below the scene loader that builds them and the finite elements that mesh them
    {"geometry"},
    {"hydro", "io"},
    {"scene"},
    {"fem"},
    {"physics"},
    # mooring lines: the catenary and the lines' term, below the assembly that adds it
    {"mooring"},
    {"solve"},
    # the liquid models (jaxslosh/liquid): each its element, blocks, term, inverse and builder; above
    # the solver pieces its inverses use, below the assembly that builds a scene's system from them
    {"liquid"},
    {"assemble"},
    {"run"},
    # the compile cache: above the runs, which reach it through staging's hooks that the entry
    # points install (cache/programs.py `install`)
    {"cache"},
    {"analysis", "campaign", "fit", "mooring.statics"},
    {"plot"},
    {"cli"},
    {"entry"},
    {"__init__", "__main__"},
]


def _modules():
    out = {}
    for dirpath, _, files in os.walk(ROOT):
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(dirpath, f)
                rel = os.path.relpath(path, ROOT)[:-3].replace(os.sep, ".")
                out[rel] = path
    return out


def _resolve(module, node):
    """The package-relative module an ImportFrom names (None for third-party imports)."""
    if node.level == 0:
        if node.module and node.module.startswith("jaxslosh."):
            return node.module[len("jaxslosh."):]
        return None
    parts = module.split(".")
    is_pkg = parts[-1] == "__init__"
    base = parts[:-1] if not is_pkg else parts[:-1]
    base = base[:len(base) - (node.level - 1)] if node.level > 1 else base
    return ".".join(base + ([node.module] if node.module else []))


def _lazy(module, node):
    """The package-relative module of `import_module("..x.y", __package__)` (None for others)."""
    if not (isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", None)) == "import_module"
            and node.args and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)):
        return None
    name = node.args[0].value
    if not name.startswith("."):
        return name[len("jaxslosh."):] if name.startswith("jaxslosh.") else None
    level = len(name) - len(name.lstrip("."))
    package = module.split(".")[:-1]
    base = package[:len(package) - (level - 1)] if level > 1 else package
    return ".".join(base + [name.lstrip(".")])


def _imports(module, path):
    tree = ast.parse(open(path).read())
    top, nested = set(), []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = {a.name[len("jaxslosh."):] for a in node.names if a.name.startswith("jaxslosh.")}
            if node in tree.body:
                top |= names
            else:
                nested += [(node.lineno, n) for n in names]
        if isinstance(node, ast.ImportFrom):
            target = _resolve(module, node)
            if target is None:
                continue
            if node.module is None:          # from . import a, b
                names = {f"{target}.{a.name}".strip(".") for a in node.names}
            else:
                names = {target}
            if node in tree.body:
                top |= names
            else:
                nested.append((node.lineno, target))
    return top, nested


def _layer(module):
    """The layer of a module: that of the longest prefix naming it (`mooring.statics` above `mooring`)."""
    best = None
    for i, layer in enumerate(LAYERS):
        for prefix in layer:
            if (module == prefix or module.startswith(prefix + ".")) and (best is None or len(prefix) > len(best[1])):
                best = (i, prefix)
    if best is None:
        raise AssertionError(f"{module} is in no layer")
    return best


MODULES = _modules()


@pytest.mark.parametrize("module", sorted(MODULES))
def test_module_is_short_and_imports_downwards_at_the_top(module):
    path = MODULES[module]
    n = sum(1 for _ in open(path))
    assert n <= 500, f"{module}: {n} lines"
    top, nested = _imports(module, path)
    assert not nested, f"{module}: package imports inside functions at lines {nested}"
    mine, pkg = _layer(module)
    for t in top:
        t = t[:-len(".__init__")] if t.endswith(".__init__") else t
        theirs, other = _layer(t if t in MODULES or t + ".__init__" in MODULES else t.rsplit(".", 1)[0])
        assert theirs < mine or other == pkg, f"{module} (layer {pkg}) imports {t} (layer {other})"


def lazy_imports(module, path):
    """(line, target) of each `import_module` of a jaxslosh module (the lazy imports that keep
    `import jaxslosh` and the command line's start light)."""
    return [(node.lineno, t) for node in ast.walk(ast.parse(open(path).read())) if (t := _lazy(module, node))]


def _layer_of_target(t):
    t = t[:-len(".__init__")] if t.endswith(".__init__") else t
    return _layer(t if t in MODULES or t + ".__init__" in MODULES else t.rsplit(".", 1)[0])


def test_no_import_goes_up_a_layer():
    """Every import, lazy ones included, goes to a lower layer or within the module's own."""
    bad = []
    for module, path in sorted(MODULES.items()):
        mine, pkg = _layer(module)
        top, _ = _imports(module, path)
        for line, t in [(0, t) for t in sorted(top)] + lazy_imports(module, path):
            theirs, other = _layer_of_target(t)
            if not (theirs < mine or other == pkg):
                bad.append(f"{module}:{line} (layer {pkg}) imports {t} (layer {other})")
    assert not bad, "\n".join(bad)


#: private names imported across top-level sub-packages that are left for now: the face-normal
#: liquid's assembly reads its element's internals (fem/liquid_rt.py), which move together into one
#: package (jaxslosh/liquid/) in the liquid's own change; nothing may be added here
PRIVATE_ALLOWED: set = set()


def private_imports(module, path) -> list:
    """(target, name) of each private name (`_x`) `module` imports from another top-level sub-package."""
    out = []
    for node in ast.walk(ast.parse(open(path).read())):
        if isinstance(node, ast.ImportFrom):
            target = _resolve(module, node)
            if target is None or target.split(".")[0] == module.split(".")[0]:
                continue
            out += [(target, a.name) for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]
    return out


def test_no_private_names_cross_sub_packages():
    bad = [(m, t, n) for m, path in sorted(MODULES.items()) for t, n in private_imports(m, path)
           if (m, t, n) not in PRIVATE_ALLOWED]
    assert not bad, bad


def test_the_private_allow_list_is_not_stale():
    found = {(m, t, n) for m, path in MODULES.items() for t, n in private_imports(m, path)}
    assert PRIVATE_ALLOWED <= found, PRIVATE_ALLOWED - found


def test_no_import_circles():
    graph = {}
    for m, path in MODULES.items():
        top, _ = _imports(m, path)
        graph[m] = {t for t in top if t in MODULES} | {t + ".__init__" for t in top if t + ".__init__" in MODULES}
    state = {}

    def visit(m, stack):
        state[m] = 1
        for t in graph.get(m, ()):
            if state.get(t) == 1:
                raise AssertionError("import circle: " + " -> ".join(stack[stack.index(t):] + [t]))
            if t not in state:
                visit(t, stack + [t])
        state[m] = 2

    for m in graph:
        if m not in state:
            visit(m, [m])


def test_only_the_compile_cache_touches_jax_internals():
    """jax._src (JAX's private modules) is read by the compile cache alone (jaxslosh/cache)."""
    bad = [m for m, path in MODULES.items() if not m.startswith("cache.") and "jax._src" in open(path).read()]
    assert not bad, bad


def test_nothing_below_the_compile_cache_imports_it():
    cache_layer, _ = _layer("cache")
    for module, path in MODULES.items():
        top, _ = _imports(module, path)
        if any(t == "cache" or t.startswith("cache.") for t in top):
            assert _layer(module)[0] > cache_layer or module.startswith("cache"), module


def test_the_finite_elements_import_neither_the_scene_nor_the_compile_cache():
    """fem/ is below the scene loader and the cache: it takes numbers and meshes, not scenes."""
    for module, path in MODULES.items():
        if module.startswith("fem."):
            top, _ = _imports(module, path)
            bad = [t for t in top if t.split(".")[0] in ("scene", "cache")]
            assert not bad, f"{module} imports {bad}"


#: the values of a tank's `shape` key (jaxslosh/geometry SHAPES)
TANK_SHAPES = {"box", "prismatic", "cylinder", "mesh"}


def _names_a_shape(node) -> bool:
    """`kind`, `x.kind`, `shape`, `x.shape`, `x["shape"]`, `x.get("shape", ...)`: where a tank's shape
    would sit as a string."""
    if isinstance(node, ast.Name):
        return node.id in ("kind", "shape")
    if isinstance(node, ast.Attribute):
        return node.attr in ("kind", "shape")
    if isinstance(node, ast.Subscript):
        return isinstance(node.slice, ast.Constant) and node.slice.value == "shape"
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get":
        return bool(node.args) and isinstance(node.args[0], ast.Constant) and node.args[0].value == "shape"
    return False


def string_constants(node) -> set:
    """The strings a comparison's side names: a constant, or the constants of a tuple, list or set
    (tests/docs/test_variant_classes.py reads them too)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return {node.value}
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return set().union(*(string_constants(e) for e in node.elts)) if node.elts else set()
    return set()


def _shape_strings(node) -> set:
    return string_constants(node) & TANK_SHAPES


def shape_branches(source: str) -> list:
    """(line, text) of each comparison of a shape-like name with a tank shape's name."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Compare):
            sides = [node.left] + node.comparators
            if any(_names_a_shape(s) for s in sides) and any(_shape_strings(s) for s in sides):
                out.append((node.lineno, ast.unparse(node)))
    return out


def test_shape_branches_are_found():
    """The finder below sees the forms a branch on a tank's shape takes."""
    src = ('a = geo.kind == "mesh"\nb = t.shape != "cylinder"\nc = kind in ("box", "prismatic")\n'
           'd = v.get("shape") == "mesh"\ne = shape["shape"] == "box"\nf = s.shape == (3, 4)\ng = hull == "box"\n')
    assert [line for line, _ in shape_branches(src)] == [1, 2, 3, 4, 5]


def test_no_string_branches_on_tank_shapes_outside_the_geometry():
    """A tank's shape is a class of jaxslosh/geometry that owns what differs between shapes (its keys,
    volume, mesh, outline, surface and words): code elsewhere calls its methods instead of asking
    which shape it holds (`geo.kind == "mesh"`, `t.shape in ("box", "prismatic")`)."""
    bad = [f"{module}:{line}: {text}" for module, path in sorted(MODULES.items()) if not module.startswith("geometry.")
           for line, text in shape_branches(open(path).read())]
    assert not bad, "\n".join(bad)
