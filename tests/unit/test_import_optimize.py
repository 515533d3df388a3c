"""Optimization and normalization preserve the drawing (property tests included)."""

from __future__ import annotations

import itertools
import math
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from plotbridge.importing.optimize import EndIndex, optimize_strokes, order_greedy, two_opt
from plotbridge.importing.optimize import travel as travel_of

from tests.fixtures.imports import drawn_strokes, program_lines, run_import

coord = st.integers(min_value=0, max_value=2000).map(lambda v: v / 10)   # 0.1 mm grid
point = st.tuples(coord, coord)
stroke = st.lists(point, min_size=2, max_size=8).filter(lambda s: len(set(s)) > 1)
drawing = st.lists(stroke, min_size=1, max_size=25)


def segments(strokes) -> list[tuple]:
    """Undirected non-degenerate segments, rounded: the drawn geometry, order-free."""
    out = []
    for s in strokes:
        for a, b in itertools.pairwise(s):
            a = (round(a[0], 3), round(a[1], 3))
            b = (round(b[0], 3), round(b[1], 3))
            if a != b:
                out.append(tuple(sorted((a, b))))
    return sorted(out)


def dist_to_polylines(p, strokes) -> float:
    best = math.inf
    for s in strokes:
        a = np.asarray(s[:-1], dtype=float)
        b = np.asarray(s[1:], dtype=float)
        d = b - a
        dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-18)
        t = np.clip(np.einsum("ij,ij->i", np.asarray(p) - a, d) / dd, 0, 1)
        q = a + t[:, None] * d
        best = min(best, float(np.min(np.hypot(*(q - p).T))))
    return best


@settings(max_examples=60, deadline=None)
@given(drawing)
def test_optimization_without_simplification_keeps_every_segment(strokes):
    out = optimize_strokes(strokes, 0.0, time.monotonic() + 0.2)
    assert segments(out) == segments(strokes)
    assert travel_of(out) <= travel_of(strokes) + 1e-6 or len(strokes) == 1
    assert len(out) <= len(strokes)


@settings(max_examples=40, deadline=None)
@given(st.lists(stroke, min_size=3, max_size=40), st.integers(min_value=1, max_value=6))
def test_two_opt_stops_only_when_no_reversal_in_the_window_helps(strokes, window):
    arrays = [np.asarray(s, dtype=float) for s in strokes]
    out = two_opt(arrays, (0.0, 0.0), time.monotonic() + 10.0, window=window)
    assert sorted(map(segments, ([s] for s in out))) == \
        sorted(map(segments, ([s] for s in arrays)))
    best = travel_of(out)
    assert best <= travel_of(arrays) + 1e-9
    for i in range(len(out) - 1):     # a run starts before the last stroke
        for j in range(i, min(len(out), i + window + 1)):
            turned = out[:i] + [s[::-1] for s in out[i:j + 1][::-1]] + out[j + 1:]
            assert travel_of(turned) >= best - 1e-6


@settings(max_examples=40, deadline=None)
@given(drawing, st.sampled_from([0.02, 0.3]))
def test_simplification_stays_within_tolerance(strokes, tol):
    out = optimize_strokes(strokes, tol, time.monotonic() + 0.2)
    for s in strokes:
        for p in s:
            assert dist_to_polylines(p, out) <= tol + 1e-9
    for s in out:
        for p in s:
            assert dist_to_polylines(p, strokes) <= 1e-9


pen_word = {
    "m3": ("M3", "M5"),
    "m300": ("M300 S30", "M300 S50"),
    "z": ("G1 Z-1 F500", "G0 Z2"),
    "z-relative": ("G1 Z-3 F500", "G0 Z3"),   # from Z2: down to Z-1, up to Z2 again
}


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(drawing, st.sampled_from(["m3", "m300", "z"]), st.booleans(), st.booleans())
def test_gcode_normalization_preserves_strokes_and_pen_state(tmp_path, strokes, dialect,
                                                             relative, inches):
    if dialect == "z" and relative:
        dialect = "z-relative"
    down, up = pen_word[dialect]
    unit = 25.4 if inches else 1.0
    lines = ["G20" if inches else "G21", "G90", "G0 Z2", "G91" if relative else "G90"]
    x = y = 0.0
    for s in strokes:
        for k, (px, py) in enumerate(s):
            if relative:
                words = f"X{(px - x) / unit:.6f} Y{(py - y) / unit:.6f}"
            else:
                words = f"X{px / unit:.6f} Y{py / unit:.6f}"
            lines.append(f"G0 {words}" if k == 0 else f"G1 {words} F{1200 / unit:.6f}")
            if k == 0:
                lines.append(down)
            x, y = px, py
        lines.append(up)
    r = run_import(tmp_path, "\n".join(lines) + "\n")
    out = drawn_strokes(program_lines(r))
    expected = [[(round(px, 3), round(py, 3)) for px, py in s] for s in strokes]
    # Zero-length moves are dropped; otherwise the same strokes in the same order.
    dedup = [[p for k, p in enumerate(s) if k == 0 or p != s[k - 1]] for s in expected]
    assert out == [s for s in dedup if len(s) > 1]
    assert program_lines(r)[-1] == "M5"


def test_greedy_order_beats_the_given_order_on_a_scrambled_grid():
    rng = np.random.default_rng(3)
    strokes = [[(x * 5.0, y * 5.0), (x * 5.0 + 3, y * 5.0)] for x in range(20) for y in range(20)]
    rng.shuffle(strokes)
    out = optimize_strokes(strokes, 0.02, time.monotonic() + 1.0)
    assert travel_of(out) < travel_of(strokes) / 10


def test_end_index_nearest_matches_brute_force():
    rng = np.random.default_rng(1)
    pts = [tuple(p) for p in rng.uniform(0, 100, (300, 2))]
    index = EndIndex(pts, 7.0)
    for k in range(0, 300, 3):
        index.remove(k)
    left = [k for k in range(300) if k % 3]
    for q in rng.uniform(-20, 120, (50, 2)):
        k = index.nearest(*q)
        brute = min(left, key=lambda i: math.dist(pts[i], q))
        assert math.dist(pts[k], q) == pytest.approx(math.dist(pts[brute], q))


def test_identical_strokes_share_one_index_entry_per_point():
    """100,000 identical tiny paths went quadratic: every query walked every end."""
    strokes = [np.array([[10.0, 10.0], [10.1, 10.0]]) for _ in range(20000)]
    ends = [(10.0, 10.0)] * 20000 + [(10.1, 10.0)] * 20000
    index = EndIndex(ends, 0.5)
    assert sum(len(points) for points in index.grid.values()) == 2
    ordered = order_greedy(strokes, (0.0, 0.0), 0.01)
    assert len(ordered) == 1 and len(ordered[0]) == 20001
