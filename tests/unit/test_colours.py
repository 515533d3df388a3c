"""Colours in words (plotbridge/colours.py): the word a person uses for a colour code, and
a layer's label, which never shows a code."""

from __future__ import annotations

import pytest
from plotbridge import colours
from plotbridge.jobs.model import Layer


@pytest.mark.parametrize(("code", "word"), [
    ("#d40000", "red"), ("#ff0000", "red"), ("#000", "black"), ("#FFFFFF", "white"),
    ("#0000ff", "blue"), ("#1f77b4", "blue"), ("#008000", "green"), ("#ffa500", "orange"),
    ("#800080", "purple"), ("#808080", "grey"), ("#ffff00", "yellow"), ("#00ffff", "cyan"),
])  # fmt: skip
def test_a_code_gets_the_word_people_use(code, word):
    assert colours.word(code) == word


def test_what_is_no_code_has_no_word_and_a_label_is_the_name_unless_a_code():
    assert colours.word("red") == "" and colours.word("#12345") == ""
    assert colours.label("outline", "#ff0000") == "outline"
    assert colours.label("#d40000") == "red"
    assert colours.label("", "#000000") == "black"
    layer = Layer(name="#d40000", colour="#d40000", first_line=1, last_line=2)
    assert layer.label == "red" and layer.model_dump()["label"] == "red"
    again = Layer(**{**layer.model_dump(), "name": "#0000ff"})  # stored, then read back
    assert again.label == "blue"
