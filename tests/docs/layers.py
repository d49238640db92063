"""The layer diagrams of docs/design.md and of jaxslosh/__init__.py's docstring, written from the
layout test's LAYERS (tests/docs/test_layout.py) and the words below: `python -m tests.docs.layers
--write` rewrites both; tests/docs/test_layer_docs.py fails while either differs."""
import importlib.util
import os
import re
import sys
import textwrap

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
DESIGN = os.path.join(REPO, "docs", "design.md")
PACKAGE_INIT = os.path.join(REPO, "jaxslosh", "__init__.py")
BEGIN = "<!-- layers: written by `python -m tests.docs.layers --write` from tests/docs/test_layout.py -->"
END = "<!-- /layers -->"
INIT_HEAD = "The package's layers, lowest first (docs/design.md):"

#: what each entry of LAYERS holds, in a few words
WORDS = {
    "__init__": "the public names, imported on first use (`js.simulate` installs the compile cache)",
    "__main__": "`python -m jaxslosh`",
    "entry": "the `jaxslosh` program: checks the scene, starts loading a run's executables, imports cli/",
    "cli": "the `jaxslosh` command: one module per command; exceptions -> messages and exit codes; "
           "`setup_jax` installs the compile cache",
    "plot": "figures: time histories, free surfaces and animations, fits, RAOs, campaigns",
    "analysis": "natural modes of a scene's liquid and structures; the linearisation about rest, RAOs, "
                "coupled modes, stability",
    "campaign": "scatter x headings x seeds on Dask: cases, statistics, workers, js.campaign",
    "fit": "identification of scene values from measured motions",
    "mooring.statics": "the moored equilibrium (js.mooring)",
    "cache": "the compile cache: programs exported and kept across processes, their executables loaded "
             "ahead; installed into staging's hooks by the entry points; the only place that touches jax._src",
    "run": "the compiled time loop (loop.py), its programs compiled ahead (compiled.py), simulate, "
           "Stepper, batches, runs to a file",
    "assemble": "scene -> System: the terms a scene has, the liquid block, probes, structures, "
                "`check`'s summary",
    "liquid": "the liquid behind one contract (base.py: AbstractLiquid), one sub-package per model: nodal/, "
              "face/, modal/, multimodal/, each its element, blocks, term, inverse and builder; shared: modes, "
              "damping, elastic walls, the block, forms.py (which model, which block)",
    "solve": "one implicit step (integrator.py), Newton and tangent solves, the structures' constant blocks "
             "(each liquid forms its own inverse)",
    "mooring": "mooring lines: the catenary and the lumped-mass lines' term",
    "physics": "what the step traces: System = the sum of its terms (AbstractTerm, Kin, Rows; the owners "
               "of unknowns); the vessel, seakeeping, structures, bodies",
    "fem": "host-side finite elements: meshes, elastic hexahedra, the tank meshes; linalg.py: inverses "
           "safe under vmap",
    "scene": "TOML -> validated, immutable Scene (no JAX); the variants' registries (hulls, waves, "
             "schemes); keys.py: the dotted keys; keydocs.py: every key's default, unit and meaning",
    "hydro": "the sea on the host: spectra, the box hull's closed forms, tables, Capytaine, radiation "
             "fit, databases",
    "io": "result, sweep, campaign and RAO files, status codes, the ParaView export",
    "geometry": "tank shapes: the abstract shape and its box, prismatic, cylinder and mesh file",
    "hull": "the hull's closed surface, its clipping at the water, hydrostatics at any angle, tanks' "
            "inner surfaces",
    "fem.shapes": "a tank's liquid at rest as a hexahedral mesh (TankMesh), what the shapes' meshers share",
    "fem.mesh": "the box mesh and its faces",
    "fem.meshfile": "a tank's liquid read from a mesh file, checked",
    "fem.slip": "slip walls: boundary faces and normals",
    "physics.kinematics": "quaternions and rotations",
    "solve.schemes": "the time schemes and their registry (plain classes, read by the scene loader)",
    "_version": "the version",
    "staging": "XLA options, `staged`, the hooks the compile cache installs",
}


def layers():
    spec = importlib.util.spec_from_file_location("_layout_for_docs", os.path.join(HERE, "test_layout.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.LAYERS


def path_of(entry: str) -> str:
    """`cli` -> cli/, `fem.mesh` -> fem/mesh.py, `entry` -> entry.py (what is in the package)."""
    base = os.path.join(REPO, "jaxslosh", *entry.split("."))
    return entry.replace(".", "/") + ("/" if os.path.isdir(base) else ".py")


def design_block() -> str:
    """The diagram of docs/design.md: highest layer first, one line per layer (wrapped)."""
    out = []
    for layer in reversed(layers()):
        names = sorted(layer)
        head = " ".join(path_of(n) for n in names)
        words = "; ".join((f"{path_of(n)}: " if len(names) > 1 else "") + WORDS[n] for n in names)
        if len(head) < 12:
            out += textwrap.wrap(words, 100, initial_indent=f"{head:<12}", subsequent_indent=" " * 12)
        else:
            out += [head] + textwrap.wrap(words, 100, initial_indent=" " * 12, subsequent_indent=" " * 12)
    return "\n".join([BEGIN, "```text"] + out + ["```", END])


def init_paragraph() -> str:
    """The docstring's paragraph: the layers lowest first, on lines of at most 100 characters."""
    text = INIT_HEAD + " " + "; ".join(", ".join(path_of(n) for n in sorted(layer)) for layer in layers()) + "."
    return "\n".join(textwrap.wrap(text, 100))


def _blocks():
    design, init = open(DESIGN).read(), open(PACKAGE_INIT).read()
    d = re.search(re.escape(BEGIN) + r".*?" + re.escape(END), design, re.S)
    i = re.search(re.escape(INIT_HEAD) + r".*?\.\n\n", init, re.S)
    return design, d, init, i


def current():
    """(the design page's block, the docstring's paragraph) as written now (None where missing)."""
    _, d, _, i = _blocks()
    return (d.group(0) if d else None), (i.group(0)[:-2] if i else None)


def write():
    design, d, init, i = _blocks()
    if d is None or i is None:
        raise SystemExit(f"no layer block found in {DESIGN if d is None else PACKAGE_INIT}")
    with open(DESIGN, "w") as f:
        f.write(design[:d.start()] + design_block() + design[d.end():])
    with open(PACKAGE_INIT, "w") as f:
        f.write(init[:i.start()] + init_paragraph() + "\n\n" + init[i.end():])


if __name__ == "__main__":
    if "--write" in sys.argv[1:]:
        write()
    else:
        print(design_block())
        print()
        print(init_paragraph())
