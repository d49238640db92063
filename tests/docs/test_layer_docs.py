"""The layer diagrams of docs/design.md and jaxslosh/__init__.py are the layout test's LAYERS
(tests/docs/layers.py writes them: `python -m tests.docs.layers --write`)."""
from layers import WORDS, current, design_block, init_paragraph, layers


def test_every_layer_entry_has_its_words():
    entries = set().union(*layers())
    assert entries <= set(WORDS), sorted(entries - set(WORDS))
    assert set(WORDS) <= entries, sorted(set(WORDS) - entries)


def test_the_diagrams_are_written_from_the_layers():
    design, init = current()
    assert design == design_block(), "docs/design.md: run `python -m tests.docs.layers --write`"
    assert init == init_paragraph(), "jaxslosh/__init__.py: run `python -m tests.docs.layers --write`"
