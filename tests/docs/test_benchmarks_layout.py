"""The benchmarks' layout (docs/benchmarks.md, benchmarks/README.md): every script under
benchmarks/speed and benchmarks/validation runs as `python -m benchmarks.<folder>.<name>` from the
repository root, says that command line in its docstring, imports no internals of the time loop
(jaxslosh/run/loop.py: the public `js.Stepper`, `js.simulate` and `js.scene_with` do that work) and
edits no `sys.path`; and the harness's table prints what it is given, aligned or as Markdown."""
import ast
import os

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FOLDERS = ("speed", "validation")
SCRIPTS = sorted((folder, name[:-3]) for folder in FOLDERS
                 for name in os.listdir(os.path.join(ROOT, "benchmarks", folder))
                 if name.endswith(".py") and name != "__init__.py")


def _tree(folder, name):
    with open(os.path.join(ROOT, "benchmarks", folder, name + ".py")) as f:
        return ast.parse(f.read())


def test_the_folders_hold_the_scripts():
    assert len(SCRIPTS) >= 20, SCRIPTS
    for folder in ("", *FOLDERS):
        assert os.path.exists(os.path.join(ROOT, "benchmarks", folder, "__init__.py")), folder
    assert os.path.exists(os.path.join(ROOT, "benchmarks", "README.md"))


@pytest.mark.parametrize("folder,name", SCRIPTS)
def test_a_script_says_its_command_line(folder, name):
    doc = ast.get_docstring(_tree(folder, name)) or ""
    assert f"python -m benchmarks.{folder}.{name}" in doc, \
        f"benchmarks/{folder}/{name}.py: no command line in its docstring"


@pytest.mark.parametrize("folder,name", SCRIPTS)
def test_a_script_imports_no_loop_internals_and_edits_no_sys_path(folder, name):
    where = f"benchmarks/{folder}/{name}.py"
    for node in ast.walk(_tree(folder, name)):
        if isinstance(node, ast.ImportFrom):
            module = node.module or ""
            assert module != "jaxslosh.run.loop", f"{where}:{node.lineno} imports jaxslosh.run.loop"
            assert not (module in ("jaxslosh.run", "run") and any(a.name == "loop" for a in node.names)), \
                f"{where}:{node.lineno} imports run/loop.py"
            assert not (node.level and module.endswith("loop")), f"{where}:{node.lineno}"
        elif isinstance(node, ast.Import):
            assert not any(a.name.startswith("jaxslosh.run.loop") for a in node.names), \
                f"{where}:{node.lineno} imports jaxslosh.run.loop"
        elif isinstance(node, ast.Attribute):
            assert not (node.attr == "path" and isinstance(node.value, ast.Name) and node.value.id == "sys"), \
                f"{where}:{node.lineno} uses sys.path"
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            # the code a script runs in a child process counts too (compile_time.py's)
            assert "jaxslosh.run.loop" not in node.value and "sys.path" not in node.value, \
                f"{where}:{node.lineno}: a string holds code that imports run/loop.py or edits sys.path"


def test_the_table_prints_aligned_text_and_markdown(monkeypatch):
    monkeypatch.syspath_prepend(ROOT)          # the benchmarks are a package of the repository root
    from benchmarks.harness import Table, parser

    t = Table(("case", "{}"), ("unknowns", "{:d}"), ("us/step", "{:.1f}"))
    t.add("vessel alone", 6, 34.24)
    t.add("paper example", 474, 1155.0)
    text = t.text().splitlines()
    assert text == ["case           unknowns  us/step",
                    "vessel alone          6     34.2",
                    "paper example       474   1155.0"]
    md = t.text(markdown=True).splitlines()
    assert md[0] == "| case          | unknowns | us/step |"
    assert md[1] == "|:--------------|---------:|--------:|"
    assert md[3] == "| paper example |      474 |  1155.0 |"
    with pytest.raises(ValueError, match="2 cells for 3 columns"):
        t.add("short", 1)
    a = parser("Doc.\n\nMore.").parse_args(["--quick", "--markdown"])
    assert a.quick and a.markdown
