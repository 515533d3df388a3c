"""preview.json's `lines`: each stroke's pen-down and pen-up program lines, so the web
preview maps progress onto strokes exactly across the M0 between layers."""

from __future__ import annotations

import json

import pytest
from plotbridge.importing import preview as preview_module
from plotbridge.program.reader import Command

from tests.fixtures.imports import program_lines, run_import

HEAD = ('<svg xmlns="http://www.w3.org/2000/svg" '
        'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" '
        'width="100mm" height="100mm" viewBox="0 0 100 100">')


def three_layers() -> str:
    return HEAD + "".join(
        f'<g inkscape:groupmode="layer" inkscape:label="{name}">'
        + "".join(f'<polyline points="{x},{y} {x + 10},{y} {x + 10},{y + 5}" fill="none" '
                  f'stroke="{colour}"/>' for x in (10, 40, 70) for y in (y0, y0 + 8)) + "</g>"
        for name, colour, y0 in (("one", "red", 10), ("two", "green", 40),
                                 ("three", "blue", 70))) + "</svg>"


def check_spans(result) -> dict:
    """Each stroke's span starts at an M3 and ends at the M5 after its last move, which
    reaches the stroke's last point; returns the preview."""
    lines = program_lines(result)
    data = json.loads(result.preview_path.read_text())
    assert len(data["lines"]) == len(data["strokes"]) == len(data["colours"])
    for stroke, (down, up) in zip(data["strokes"], data["lines"], strict=True):
        assert lines[down - 1] == "M3" and lines[up - 1] == "M5"
        assert all(not t.startswith(("M", "G0")) for t in lines[down:up - 1])
        last = Command.parse(lines[up - 2])
        assert (last.x, last.y) == pytest.approx(tuple(stroke[-1]), abs=1e-3)
    return data


def test_spans_skip_the_m0_between_layers(tmp_path):
    r = run_import(tmp_path, three_layers(), "d.svg")
    data = check_spans(r)
    assert [lay["name"] for lay in r.layers] == ["one", "two", "three"]
    m0 = [n for n, t in enumerate(program_lines(r), 1) if t == "M0"]
    assert m0 == [lay["first_line"] - 1 for lay in r.layers[1:]]
    # every stroke of a layer lies inside its lines, in the layer's colour
    spans = data["lines"]
    for lay in r.layers:
        mine = [k for k, (down, _) in enumerate(spans)
                if lay["first_line"] <= down <= lay["last_line"]]
        assert len(mine) == lay["strokes"] == 6
        assert {data["colours"][k] for k in mine} == {lay["colour"]}


def test_spans_of_strokes_longer_than_a_batch(tmp_path, monkeypatch):
    monkeypatch.setattr(preview_module, "_BATCH", 8)   # pieces continue across batches
    def zigzag(y0: int) -> str:
        return " ".join(f"{1 + x},{y0 + (x * 7) % 13}" for x in range(40))
    doc = HEAD + "".join(f'<polyline points="{zigzag(y0)}" fill="none" stroke="black"/>'
                         for y0 in (5, 40, 70)) + "</svg>"
    data = check_spans(run_import(tmp_path, doc, "d.svg", optimize=False))
    assert len(data["lines"]) == 3


def test_spans_of_gcode_with_arcs_and_dwells(tmp_path):
    text = ("G21\nG90\nG0 X10 Y10\nM3\nG4 P0.1\nG1 X20 Y10 F1000\nG2 X30 Y20 I0 J10\nM5\n"
            "M0\nG0 X50 Y50\nM3\nG1 X60 Y50\nM5\n")
    data = check_spans(run_import(tmp_path, text, "d.gcode"))
    assert len(data["lines"]) == 2
