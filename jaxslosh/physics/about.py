"""What a term says of itself in `jaxslosh check`: `About`, the (effect, text) lines that assembly
writes on a term where the term's arrays alone cannot say it (a tank's name and mesh, a wave
spectrum's parameters, a hull's file).

An `About` is a static field of its term, so it is never traced; and it is not part of the program
either: every `About` equals every other, hashes alike and pickles without its lines. Two models
that differ only in their descriptions (two scenes with other wave heights, say) then have one tree
structure, share their compiled programs in this process and their files in the compile cache
(cache/programs.py names a program by its pickled tree structure). A model read back from that
cache has lost its lines; `check` describes the model it assembles itself.
"""
from __future__ import annotations


class About:
    """(effect, text) lines describing a term, as `jaxslosh check` prints them: `- effect: text`."""
    __slots__ = ("lines",)

    def __init__(self, *lines: tuple[str, str]):
        self.lines = tuple((str(e), str(t)) for e, t in lines)

    def __eq__(self, other):
        return isinstance(other, About)

    def __hash__(self):
        return hash(About)

    def __reduce__(self):
        return (About, ())

    def __add__(self, other: "About") -> "About":
        return About(*self.lines, *other.lines)

    def __repr__(self):
        return f"About({len(self.lines)} lines)"


#: how the text of a line that a term adds for a [[bodies]] body begins (a mooring line on that body):
#: `jaxslosh check` lists it under that body's own line (assemble/check.py)
HELD = "on the body {!r}: "


def held_by(name: str, text: str) -> str:
    """`text` of a line that belongs to the body `name`, as `check` finds it (HELD)."""
    return HELD.format(name) + text


def holder(text: str):
    """(the body's name, the text without HELD) of a line that held_by wrote; (None, text) otherwise."""
    head = HELD.split("{")[0]
    if text.startswith(head) and "': " in text:
        name, rest = text[len(head) + 1:].split("': ", 1)
        return name, rest
    return None, text
