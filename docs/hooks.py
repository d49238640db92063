"""mkdocs hooks (mkdocs.yml `hooks:`): the pages generated from the code at build time.

- `reference/scene.md`: every scene key from the key registry (jaxslosh/scene/keydocs.py), with its
  default, unit and meaning, and whether `params`, `sweep` and `identify` may trace it;
- `reference/commands.md`: every command of the `jaxslosh` parser (jaxslosh/cli), its usage and
  its arguments' help;
- `reference/api.md`: the public names of `jaxslosh` (its `__init__`), rendered by mkdocstrings;
- the guides: every `docs/guide/*.md` that mkdocs.yml's nav does not list is added to its "Guides"
  section, so a new guide needs no edit of mkdocs.yml;
- the notebooks' math: the `$...$` and `$$...$$` of their Markdown cells written as MathML at build
  time (`render_math`), which browsers draw without a script: the site loads nothing from elsewhere
  (no MathJax or KaTeX from a CDN, no web fonts: mkdocs.yml `theme.font: false`) and reads offline.

The generators are plain functions returning Markdown, so tests/docs/test_docs.py checks them without
running mkdocs.
"""
from __future__ import annotations

import argparse
import html as _html
import os
import re

HERE = os.path.dirname(os.path.abspath(__file__))
GENERATED = ("reference/scene.md", "reference/commands.md", "reference/api.md")


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


# ------------------------------------------------------------------------------------------------
# the scene reference
def _table_of(key: str, tables) -> str:
    best = ""
    for t in tables:
        if t and key.startswith(t + ".") and len(t) > len(best):
            best = t
    return best


def _traceable(key: str) -> bool:
    from jaxslosh.scene.keys import TRACEABLE
    for group in ("tanks", "mooring", "connections", "bodies"):    # named tables: any name stands for <name>
        if key.startswith(group + "."):
            return (f"{group}.T." + key[len(group) + 1:]) in TRACEABLE
    return key in TRACEABLE


def scene_reference() -> str:
    """The scene reference page: one section per table, one row per key."""
    from jaxslosh.scene.keydocs import KEYS, TABLES
    names = [t for t, _ in TABLES]
    rows: dict[str, list] = {t: [] for t in names}
    for key, default, unit, meaning in KEYS:
        rows[_table_of(key, names)].append((key, default, unit, meaning))
    out = ["# Scene reference", "",
           "Every key a scene file may hold, generated from the key registry "
           "(`jaxslosh/scene/keydocs.py`). Units are SI, angles radians. A key is written as in the "
           "file without indices: `tanks.fluid.density` is the `density` of the `[tanks.fluid]` table "
           "of any `[[tanks]]`. In Python, `params`, `jaxslosh sweep --param` and "
           "`jaxslosh identify --fit` name a value by its dotted path with the tank's name or index "
           "(`tanks.tank.fill_depth`, `tanks[0].fill_depth`); the keys marked *traced* are the ones "
           "they may trace (gradients, batches, fits).", ""]
    for table, what in TABLES:
        if not rows[table]:
            continue
        title = f"`[{table}]`" if table else "Top level"
        if table in ("tanks", "structures", "probes", "tanks.baffles"):
            title = f"`[[{table}]]`"
        out += [f"## {title}", "", what, "", "| key | default | unit | meaning |", "| --- | --- | --- | --- |"]
        for key, default, unit, meaning in rows[table]:
            traced = " *traced*" if _traceable(key) else ""
            out.append(f"| `{key}`{traced} | {_cell(default)} | {_cell(unit)} | {_cell(meaning)} |")
        out.append("")
    return "\n".join(out)


# ------------------------------------------------------------------------------------------------
# the command reference
def _subparser(name: str) -> argparse.ArgumentParser:
    from jaxslosh.cli.main import parser
    p = parser([name])
    for action in p._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action.choices[name]
    raise LookupError(name)


#: the meaning of arguments the parsers leave without help
_PLAIN = {"scene": "the scene file (TOML)", "result": "a result file (also a sweep or campaign file for `plot`)",
          "tank": "the tank's name", "structure": "the structure's name"}


def command_names() -> list[str]:
    """The commands of the `jaxslosh` parser."""
    from jaxslosh.cli.main import parser
    p = parser([])
    for action in p._actions:
        if isinstance(action, argparse._SubParsersAction):
            return list(action.choices)
    return []


def command_reference() -> str:
    """The command reference page: one section per command, its usage and an argument table."""
    from jaxslosh.cli.common import COMMANDS
    out = ["# Command reference", "",
           "Every command of `jaxslosh` (also `python -m jaxslosh`), generated from its argument "
           "parser (`jaxslosh/cli/`). Exit status: 0 done, 2 bad input (one line on stderr naming "
           "the key, file or option), 3 numerical failure (the result file keeps the steps before "
           "it), 130 interrupted, 1 the output could not be written.", ""]
    for name in command_names():
        sp = _subparser(name)
        fmt = sp._get_formatter()
        usage = " ".join(sp.format_usage().split())
        usage = usage[len("usage: "):] if usage.startswith("usage: ") else usage
        out += [f"## `{name}`", "", _cell(COMMANDS.get(name, ("", ""))[1]).capitalize() + ".", "",
                "```text", usage, "```", "", "| argument | default | meaning |", "| --- | --- | --- |"]
        for action in sp._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            if action.option_strings:
                arg = ", ".join(action.option_strings)
                if action.nargs != 0:
                    arg += " " + (action.metavar or action.dest.upper())
            else:
                arg = action.metavar or action.dest.upper()
            default = "" if action.default in (None, False, argparse.SUPPRESS) or not action.option_strings \
                else f"`{action.default}`"
            text = fmt._expand_help(action) if action.help else _PLAIN.get(action.dest, "")
            if action.choices and not isinstance(action.choices, dict):
                text += f" (one of {', '.join(map(str, action.choices))})"
            out.append(f"| `{_cell(arg)}` | {_cell(default)} | {_cell(text)} |")
        out.append("")
    return "\n".join(out)


# ------------------------------------------------------------------------------------------------
# the API reference
def public_api() -> dict[str, str]:
    """Each public name of `jaxslosh` and the dotted path of the object mkdocstrings renders."""
    import jaxslosh
    out = {}
    for name in jaxslosh.__all__:
        if name == "__version__":
            continue
        if name in ("campaign", "mooring"):      # functions named as their sub-packages
            out[name] = {"campaign": "jaxslosh.campaign.run.campaign", "mooring": "jaxslosh.mooring.statics.mooring"}[name]
            continue
        out[name] = "jaxslosh" + jaxslosh._PUBLIC[name] + "." + name
    return out


def api_reference() -> str:
    out = ["# Python API", "",
           "The public names of `jaxslosh` (`import jaxslosh as js`), generated from their docstrings. "
           "Switch on float64 first: `jax.config.update(\"jax_enable_x64\", True)`. "
           "The [Python API guide](../guide/python-api.md) shows them at work.", ""]
    for name, path in sorted(public_api().items(), key=lambda kv: kv[0].lower()):
        out += [f"::: {path}", "    options:", "      show_root_heading: true",
                "      show_root_full_path: false", "      heading_level: 2", ""]
    return "\n".join(out)


# ------------------------------------------------------------------------------------------------
# mkdocs events
def _listed(nav) -> set:
    found = set()
    for item in nav or []:
        if isinstance(item, str):
            found.add(item)
        elif isinstance(item, dict):
            for value in item.values():
                if isinstance(value, str):
                    found.add(value)
                else:
                    found |= _listed(value)
    return found


def on_config(config, **kwargs):
    nav = config.get("nav")
    if not nav:
        return config
    listed = _listed(nav)
    guide_dir = os.path.join(config["docs_dir"], "guide")
    extra = sorted(f"guide/{f}" for f in os.listdir(guide_dir) if f.endswith(".md") and f"guide/{f}" not in listed)
    for item in nav:
        if isinstance(item, dict) and "Guides" in item:
            for page in extra:
                item["Guides"].append(page)
    return config


def on_files(files, config, **kwargs):
    from mkdocs.structure.files import File
    pages = {"reference/scene.md": scene_reference, "reference/commands.md": command_reference,
             "reference/api.md": api_reference}
    for uri, make in pages.items():
        files.append(File.generated(config, uri, content=make()))
    return files


#: mkdocs-jupyter's (nbconvert's) block that would load MathJax from a URL it leaves empty
_MATHJAX_BLOCK = re.compile(r"<!-- Load mathjax -->.*?<!-- End of mathjax configuration -->", re.S)
_TAG = re.compile(r"(<[^>]*>)")
_RAW = ("pre", "code", "script", "style", "textarea", "math")
_DISPLAY = re.compile(r"\$\$(.+?)\$\$", re.S)
_INLINE = re.compile(r"(?<![\\$])\$([^$\n]+?)\$")


def _mathml(latex: str, display: str) -> str:
    from latex2mathml.converter import convert

    return convert(_html.unescape(latex).strip(), display=display)


def render_math(page_html: str) -> str:
    """The `$$...$$` (display) and `$...$` (inline) TeX of a notebook page's text as MathML, outside
    code, scripts and styles; mkdocs-jupyter's MathJax loader removed. A page without math comes
    back as it was, but for that loader."""
    page_html = _MATHJAX_BLOCK.sub("", page_html)
    parts = _TAG.split(page_html)
    raw = []                        # the enclosing elements whose text is not prose
    for i, part in enumerate(parts):
        if i % 2:                   # a tag
            m = re.match(r"<(/?)([a-zA-Z][\w-]*)", part)
            if m and m.group(2).lower() in _RAW and not part.endswith("/>"):
                if m.group(1):
                    if raw and raw[-1] == m.group(2).lower():
                        raw.pop()
                else:
                    raw.append(m.group(2).lower())
        elif not raw and "$" in part:
            part = _DISPLAY.sub(lambda t: _mathml(t.group(1), "block"), part)
            parts[i] = _INLINE.sub(lambda t: _mathml(t.group(1), "inline"), part)
    return "".join(parts)


def on_post_page(output, page, config, **kwargs):
    if page.file.src_uri.endswith(".ipynb"):
        return render_math(output)
    return output
