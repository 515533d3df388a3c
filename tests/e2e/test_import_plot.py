"""End to end: an SVG with transforms, arcs and curves is imported, its normalized
program streamed to the real firmware in the virtual plotter, and what the pen drew
(the simulator's trace) compared with the SVG's own geometry."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from plotbridge.importing import ImportOptions, MachineProfile, import_file

from tests.fixtures.grbl_sender import Board

pytestmark = pytest.mark.e2e


SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="120mm" height="100mm"
     viewBox="0 0 240 200">
  <g transform="translate(120,100) rotate(30) scale(1.5)">
    <rect x="-10" y="-10" width="20" height="20" fill="none" stroke="black"/>
    <circle cx="0" cy="0" r="15" fill="none" stroke="black"/>
  </g>
  <path d="M 20 180 A 40 40 0 0 1 100 180" fill="none" stroke="black"/>
  <path d="M 140 160 C 160 120 200 200 220 160" fill="none" stroke="black"/>
</svg>
"""


def reference_geometry() -> list[np.ndarray]:
    """The SVG above computed by hand, in plotter millimetres: 0.5 mm per user unit,
    Y flipped about the 100 mm page height."""
    def page(x, y):
        return np.c_[np.asarray(x) * 0.5, 100 - np.asarray(y) * 0.5]

    a = math.radians(30)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])

    def group(pts):
        p = (rot @ (1.5 * np.asarray(pts, dtype=float)).T).T + np.array([120.0, 100.0])
        return page(p[:, 0], p[:, 1])

    square = np.array([(-10, -10), (10, -10), (10, 10), (-10, 10), (-10, -10)], dtype=float)
    t = np.linspace(0, 2 * math.pi, 2000)
    circle = np.c_[15 * np.cos(t), 15 * np.sin(t)]
    h = np.linspace(0, math.pi, 2000)      # upper half (on screen) of the r=40 arc
    arc = page(60 - 40 * np.cos(h), 180 - 40 * np.sin(h))
    u = np.linspace(0, 1, 2000)[:, None]
    ctrl = np.array([(140, 160), (160, 120), (200, 200), (220, 160)], dtype=float)
    bez = ((1 - u) ** 3 * ctrl[0] + 3 * (1 - u) ** 2 * u * ctrl[1]
           + 3 * (1 - u) * u ** 2 * ctrl[2] + u ** 3 * ctrl[3])
    return [group(square), group(circle), arc, page(bez[:, 0], bez[:, 1])]


def distances(points: np.ndarray, polylines: list[np.ndarray]) -> np.ndarray:
    """Distance from each point to the nearest segment of the polylines."""
    a = np.concatenate([p[:-1] for p in polylines])
    d = np.concatenate([p[1:] for p in polylines]) - a
    dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-18)
    out = np.empty(len(points))
    for k in range(0, len(points), 256):
        rel = points[k:k + 256, None, :] - a[None]
        t = np.clip(np.einsum("pij,ij->pi", rel, d) / dd, 0, 1)
        off = rel - t[..., None] * d
        out[k:k + 256] = np.sqrt(np.min(np.einsum("pij,pij->pi", off, off), axis=1))
    return out



def plot(plotter, program: Path) -> dict:
    """Streams a normalized program from an unlocked machine at 0,0; returns the trace."""
    board = Board(plotter.port)
    try:
        board.command("$X")
        board.stream(program.read_text().splitlines())
        board.wait_idle()
    finally:
        board.close()
    return plotter.trace()


def test_svg_with_transforms_and_arcs_plots_its_geometry(plotter, tmp_path):
    src = tmp_path / "drawing.svg"
    src.write_text(SVG)
    result = import_file(src, "drawing.svg", tmp_path / "job", ImportOptions(), MachineProfile())
    trace = plot(plotter, result.program_path)

    reference = reference_geometry()
    strokes = [np.asarray(s, dtype=float)[:, :2] for s in trace["strokes"] if len(s) > 1]
    assert strokes, trace
    drawn = np.concatenate(strokes)
    # Everything the pen drew is on the SVG's shapes ...
    off = distances(drawn, reference)
    assert off.max() <= 0.05, f"drawn point {drawn[off.argmax()]} is {off.max():.3f} mm off"
    # ... and every part of the shapes was drawn.
    ref_points = np.concatenate([r[::10] for r in reference])
    missing = distances(ref_points, strokes)
    assert missing.max() <= 0.05, \
        f"{ref_points[missing.argmax()]} not drawn ({missing.max():.3f} mm from the trace)"
    assert trace["pen_lifts"] == result.stats["pen_lifts"]
    assert trace["draw_mm"] == pytest.approx(result.stats["pen_down_mm"], rel=0.01)
    assert all(v == 0 for v in trace["violations"].values())
