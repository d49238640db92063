"""What the package, the docs, the scenes, the benchmarks and the notebooks cite is what a user has:
pages under docs/ (or the README's own sections), never the project's private notes (SPEC.md,
PHYSICS.md, STYLE.md), which `jaxslosh check` and the docs once cited ("PHYSICS.md item 5")."""
import json
import os
import re

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# docs/hooks.py writes these at build time: they are cited, and exist only in the built site
GENERATED = {"docs/reference/scene.md", "docs/reference/commands.md", "docs/reference/api.md"}
WHERE = ["jaxslosh", "docs", "README.md", "benchmarks", "notebooks", "scenes"]
TEXT = (".py", ".md", ".toml", ".ipynb", ".yml", ".yaml", ".txt", ".cfg", ".csv")

PRIVATE = re.compile(r"\bSPEC\b|SPEC\.md|\bPHYSICS\b|PHYSICS\.md|STYLE\.md")
README_CITED = re.compile(r"README,? \"([^\"]+)\"")
DOCS_PATH = re.compile(r"docs/[\w./-]*\w\.md")
THEORY_ITEM = re.compile(r"docs/theory\.md,?\s+items?\s+(\d+)(?:-(\d+))?")


def files():
    for w in WHERE:
        p = os.path.join(ROOT, w)
        if os.path.isfile(p):
            yield w
            continue
        for d, dirs, names in os.walk(p):
            dirs[:] = [x for x in dirs if x not in ("__pycache__", ".ipynb_checkpoints")]
            for n in names:
                if n.endswith(TEXT):
                    yield os.path.relpath(os.path.join(d, n), ROOT)


def text_of(rel):
    """A file's text; a notebook's sources and text outputs (not its images' base64)."""
    with open(os.path.join(ROOT, rel), encoding="utf-8") as f:
        raw = f.read()
    if not rel.endswith(".ipynb"):
        return raw
    parts = []
    for cell in json.loads(raw)["cells"]:
        parts.append("".join(cell.get("source", "")))
        for out in cell.get("outputs", []):
            parts.append("".join(out.get("text", "")))
            parts.append("".join(out.get("data", {}).get("text/plain", "")))
    return "\n".join(parts)


FILES = sorted(files())


def test_the_files_are_found():
    assert "jaxslosh/cli/main.py" in FILES and "README.md" in FILES and "docs/theory.md" in FILES
    assert any(f.endswith(".ipynb") for f in FILES) and any(f.startswith("scenes/") for f in FILES)


def test_no_private_notes_cited():
    hits = [f"{rel}:{text_of(rel)[:m.start()].count(chr(10)) + 1}: {m.group(0)}"
            for rel in FILES for m in PRIVATE.finditer(text_of(rel))]
    assert not hits, "cite a page under docs/ instead:\n" + "\n".join(hits)


def test_the_finder_sees_the_forms():
    for s in ("SPEC section 8", "(SPEC)", "SPEC's form", "SPEC.md", "PHYSICS section 5", "PHYSICS.md item 5",
              "STYLE.md habit 3"):
        assert PRIVATE.search(s), s
    for s in ("SPECTRUM_FLOOR", "spectrum", "spec.toml", "SPECTRUM_SHOWN"):
        assert not PRIVATE.search(s), s


def readme_sections():
    with open(os.path.join(ROOT, "README.md"), encoding="utf-8") as f:
        return {ln.lstrip("#").strip() for ln in f if ln.startswith("#")}


def test_readme_sections_cited_exist():
    have = readme_sections()
    bad = [f"{rel}: README \"{m.group(1)}\"" for rel in FILES for m in README_CITED.finditer(text_of(rel))
           if m.group(1) not in have]
    assert not bad, "sections the README no longer has (cite the docs page):\n" + "\n".join(bad)


def test_docs_pages_cited_exist():
    cited = {}
    for rel in FILES:
        if rel.startswith("docs/") and rel.endswith(".md"):
            continue                        # pages link relatively; mkdocs --strict checks those
        for m in DOCS_PATH.finditer(text_of(rel)):
            cited.setdefault(m.group(0), rel)
    assert "docs/theory.md" in cited
    missing = {p: rel for p, rel in cited.items() if p not in GENERATED and not os.path.isfile(os.path.join(ROOT, p))}
    assert not missing, missing


def test_theory_items_cited_exist():
    """"docs/theory.md item 5": the numbered list of what the paper leaves out (its only numbered list)."""
    with open(os.path.join(ROOT, "docs", "theory.md"), encoding="utf-8") as f:
        theory = f.read()
    section = theory.split("## What the paper leaves out", 1)[1].split("\n## ", 1)[0]
    n = len(re.findall(r"^\d+\. ", section, re.M))
    assert n >= 10
    assert len(re.findall(r"^\d+\. ", theory, re.M)) == n          # "item N" is unambiguous
    bad = [f"{rel}: {m.group(0)}" for rel in FILES for m in THEORY_ITEM.finditer(text_of(rel))
           if int(m.group(2) or m.group(1)) > n]
    assert not bad, bad


DOCS_SECTION = re.compile(r"(docs/[\w./-]*\w\.md),? \"([^\"]+)\"")


def _plain(title: str) -> str:
    """Code marks, quotes and the comment marks of a title continued on the next comment line dropped."""
    title = re.sub(r"\n\s*(#|//)*", " ", title)
    return " ".join(title.replace("`", "").replace('"', "").split())


def test_docs_sections_cited_exist():
    """`docs/guide/liquid-element.md, "Why rt"`: the page has that heading (code marks and quotes aside)."""
    bad = []
    for rel in FILES:
        if rel.startswith("docs/") and rel.endswith(".md"):
            continue
        for m in DOCS_SECTION.finditer(text_of(rel)):
            page, title = m.groups()
            if page in GENERATED or not os.path.isfile(os.path.join(ROOT, page)):
                continue                    # a missing page is test_docs_pages_cited_exist's
            with open(os.path.join(ROOT, page), encoding="utf-8") as f:
                heads = {_plain(ln.lstrip("#")) for ln in f if ln.startswith("#")}
            if _plain(title) not in heads:
                bad.append(f"{rel}: {page}, \"{title}\"")
    assert not bad, "sections the pages do not have:\n" + "\n".join(bad)
