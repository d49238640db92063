"""The documentation site as a reader sees it: every notebook page shows its outputs (the notebooks
are stored executed: mkdocs-jupyter renders them, it does not run them), its math drawn (the
`$...$` written as MathML at build time by docs/hooks.py, not left as raw TeX), and the site loads
nothing from elsewhere (no web fonts, no script from a CDN), so that it reads offline.

The fast tests read the notebooks' JSON and call the hooks' rendering directly; the slow one
builds the site with mkdocs and reads the pages it wrote."""
import importlib.util
import json
import os
import re
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
NOTEBOOKS = sorted(f for f in os.listdir(os.path.join(ROOT, "notebooks")) if f.endswith(".ipynb"))


def _hooks():
    spec = importlib.util.spec_from_file_location("docs_hooks_site", os.path.join(ROOT, "docs", "hooks.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _notebook(name):
    with open(os.path.join(ROOT, "notebooks", name), encoding="utf-8") as f:
        return json.load(f)


def test_all_notebooks_are_in_the_nav():
    with open(os.path.join(ROOT, "mkdocs.yml")) as f:
        nav = f.read()
    assert len(NOTEBOOKS) >= 8
    for name in NOTEBOOKS:
        assert f"notebooks/{name}" in nav, name


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_notebook_is_stored_with_its_outputs(name):
    """Every code cell was run and its outputs kept; the page shows at least one figure."""
    cells = [c for c in _notebook(name)["cells"] if c["cell_type"] == "code" and "".join(c["source"]).strip()]
    assert cells
    not_run = [i for i, c in enumerate(cells) if c.get("execution_count") is None]
    assert not not_run, f"{name}: code cells stored without being run: {not_run}"
    outputs = [o for c in cells for o in c.get("outputs", [])]
    assert outputs, f"{name}: no outputs stored"
    errors = [o for o in outputs if o.get("output_type") == "error"]
    assert not errors, f"{name}: a cell raised: {errors[0].get('ename')}"
    images = [o for o in outputs if any(k.startswith("image/") for k in o.get("data", {}))]
    assert images, f"{name}: no figure stored"


def test_notebooks_stay_small():
    """Stored outputs are for reading: the repository and the site stay light."""
    for name in NOTEBOOKS:
        size = os.path.getsize(os.path.join(ROOT, "notebooks", name))
        assert size < 2_500_000, (name, size)


def _markdown_math(nb) -> int:
    src = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown")
    return len(re.findall(r"\$\$.+?\$\$|(?<![\\$])\$[^$\n]+?\$", src, re.S))


def _prose(page_html: str) -> str:
    """The text a reader sees, outside code, scripts, styles and math."""
    h = re.sub(r"<(script|style|pre|code|math)\b.*?</\1>", "", page_html, flags=re.S)
    return re.sub(r"<[^>]+>", "", h)


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_notebook_math_is_rendered(name):
    """The Markdown cells as nbconvert writes them (mkdocs-jupyter's converter), through the hook:
    as many MathML elements as TeX spans, no `$` left."""
    from nbconvert.filters.markdown_mistune import markdown2html_mistune

    hooks = _hooks()
    nb = _notebook(name)
    html = "\n".join(markdown2html_mistune("".join(c["source"])) for c in nb["cells"] if c["cell_type"] == "markdown")
    out = hooks.render_math(html)
    assert "$" not in _prose(out), [ln for ln in _prose(out).splitlines() if "$" in ln][:3]
    assert out.count("<math") == _markdown_math(nb)


def test_the_four_pages_of_the_issue_have_math():
    assert all(_markdown_math(_notebook(n)) for n in
               ("anti_roll_tank.ipynb", "parametric_roll.ipynb", "quickstart.ipynb", "waves.ipynb"))


def test_render_math_leaves_code_and_drops_the_mathjax_loader():
    hooks = _hooks()
    page = ('<!-- Load mathjax -->\n<script src=""> </script><script>inlineMath: [["$","$"]]</script>'
            '<!-- End of mathjax configuration -->'
            '<p>closed form $\\omega^2 = g k \\tanh(k h)$ and</p><p>$$\\mu = \\frac{m_1 L^2}{I},$$</p>'
            '<pre><code>echo $HOME $PATH</code></pre><p>a price of \\$5</p>')
    out = hooks.render_math(page)
    assert "mathjax" not in out.lower() and '<script src="">' not in out
    assert out.count('<math xmlns="http://www.w3.org/1998/Math/MathML" display="inline">') == 1
    assert out.count('display="block"') == 1 and "<mfrac>" in out
    assert "<code>echo $HOME $PATH</code>" in out
    assert "\\omega" not in out


def test_the_theme_loads_no_web_fonts():
    import yaml

    with open(os.path.join(ROOT, "mkdocs.yml")) as f:
        config = yaml.load(f, Loader=yaml.SafeLoader)
    assert config["theme"].get("font") is False
    for key in ("extra_javascript", "extra_css"):
        assert not [u for u in config.get(key, []) if "//" in str(u)], key


# what a page may name elsewhere: links a reader follows, not resources the page loads
_LOADS = re.compile(r"<(?:script|img|link|iframe|source|video|audio)\b[^>]*?\b(?:src|href)=\"((?:https?:)?//[^\"]+)\"")
_CSS_URL = re.compile(r"url\(\s*['\"]?((?:https?:)?//[^)'\"]+)|@import\s+['\"]?(?:url\()?['\"]?((?:https?:)?//[^'\")]+)")


@pytest.mark.slow
def test_built_site(tmp_path):
    """mkdocs build --strict, then every notebook page: its figures there, no `$` in its text, and no
    page or stylesheet that loads anything from elsewhere (about 30 s)."""
    pytest.importorskip("mkdocs")
    pytest.importorskip("latex2mathml")
    site = tmp_path / "site"
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    p = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(site)], cwd=ROOT,
                       env=env, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    for name in NOTEBOOKS:
        page = (site / "notebooks" / name[:-len(".ipynb")] / "index.html").read_text(encoding="utf-8")
        assert "jp-OutputArea-output" in page and re.search(r"<img[^>]+src=\"data:image/", page), name
        assert "$" not in _prose(page), (name, [ln for ln in _prose(page).splitlines() if "$" in ln][:3])
    loads = []
    for d, _, files in os.walk(site):
        for f in files:
            path = os.path.join(d, f)
            if f.endswith(".html"):
                loads += [(path, u) for u in _LOADS.findall(open(path, encoding="utf-8").read())]
            elif f.endswith(".css"):
                loads += [(path, u) for m in _CSS_URL.findall(open(path, encoding="utf-8").read()) for u in m if u]
    assert not loads, loads[:5]
