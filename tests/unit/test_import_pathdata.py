"""SVG path data, number lists, transforms and CSS read in linear time, drawn up to the
first error: checked against svgelements on valid data, against SVG's error rules on
broken data, and fuzzed with a CPU-time bound per input (no input may make a reader
backtrack: the bound grows with the input's length only)."""

from __future__ import annotations

import math
import os
import time

import numpy as np
import pytest
import svgelements as se
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from plotbridge.importing import curves, pathdata, svgstyle
from plotbridge.importing.svgstyle import Stylesheet, cascade
from plotbridge.importing.svgxml import parse_svg_xml

REDOS = ("M0 0L10.5 10.5L10.5 10.5L10.5 10.5L10.5 10.5L10.5 10.5L10.5 10.5"
         "A1 1 0 0 1 2 2")


def svgelements_subpaths(d: str, tol: float) -> list[tuple[np.ndarray, bool]]:
    """The same flattening over svgelements' segments (its own parser), for comparison."""
    out, cur, closed = [], [], False
    for seg in se.Path(d):
        if isinstance(seg, se.Move):
            if cur:
                out.append((np.vstack(cur), closed))
            cur, closed = [np.array([[seg.end.x, seg.end.y]])], False
            continue
        if isinstance(seg, se.Close):
            if (seg.start.x, seg.start.y) != (seg.end.x, seg.end.y):
                cur.append(np.array([[seg.end.x, seg.end.y]]))
            closed = True
        elif isinstance(seg, se.Line):
            if closed:      # a drawing command after Z starts a subpath at the start
                out.append((np.vstack(cur), closed))
                cur, closed = [np.array([[seg.start.x, seg.start.y]])], False
            cur.append(np.array([[seg.end.x, seg.end.y]]))
        elif isinstance(seg, (se.QuadraticBezier, se.CubicBezier)):
            pts = [seg.start, seg.control, seg.end] if isinstance(seg, se.QuadraticBezier) \
                else [seg.start, seg.control1, seg.control2, seg.end]
            cur.append(pathdata.bezier(np.array([[p.x, p.y] for p in pts]), tol))
    if cur:
        out.append((np.vstack(cur), closed))
    return out


@pytest.mark.parametrize("d", [
    "M 10 10 L 20 20 30 10 Z",
    "m10,10 20,0 0,20 -20,0z m 5 5 l 1 1",
    "M1-2L3.5.5H10V-3h2v-2Z M 4 4 L 5 5",
    "M0 0C10 0 10 10 20 10S30 20 40 20",
    "M0 0c10 0 10 10 20 10 5 5 5 5 10 0q 3 3 6 0Q 50 50 60 60 T 70 70 t 5 -5",
    "M 1e1 2E-1 l 1e0 1 M 3 3 4 4",
    "M -0 -0 L -0 5",
    "M0 0 L 10 0 L 10 10 Z L 20 20",
])
def test_path_data_reads_as_svgelements_reads_it(d):
    ours = curves.path_subpaths(d, 0.01)
    theirs = svgelements_subpaths(d, 0.01)
    assert [c for _, c in ours] == [c for _, c in theirs]
    for (a, _), (b, _) in zip(ours, theirs, strict=True):
        assert a.shape == b.shape and np.allclose(a, b, atol=1e-9), (a, b)


@pytest.mark.parametrize("d", [
    "M 5 5 A 3 3 0 0 1 10 10", "M 5 5 a 3 6 30 1 0 10 10", "M0 0 A 1 1 0 0 1 20 0",
    "M 5 5 a3,3 0 1,1 10,0", "M5 5a3 3 0 1110 0",
])
def test_arcs_lie_on_the_ellipse_svgelements_finds(d):
    (pts, _), = curves.path_subpaths(d, 0.001)
    arc = next(s for s in se.Path(d) if isinstance(s, se.Arc))
    assert np.allclose(pts[-1], (arc.end.x, arc.end.y))
    phi = math.radians(arc.get_rotation().as_degrees)
    c, s = math.cos(phi), math.sin(phi)
    dx, dy = pts[:, 0] - arc.center.x, pts[:, 1] - arc.center.y
    u, v = (c * dx + s * dy) / arc.rx, (-s * dx + c * dy) / arc.ry
    assert np.allclose(u * u + v * v, 1.0, atol=1e-6)
    # the same side of the ellipse: svgelements' points lie on ours
    for t in (0.25, 0.5, 0.75):
        p = arc.point(t)
        assert np.hypot(pts[:, 0] - p.x, pts[:, 1] - p.y).min() < 0.05 * max(arc.rx, arc.ry)


@pytest.mark.parametrize(("d", "drawn", "error"), [
    ("M 1 1 L 2", [[(1, 1)]], "'L' has too few numbers"),
    ("L 1 1 2 2", [], "must start with a moveto"),
    ("M 0 0 L 5 5 L 6 x 7 7", [[(0, 0), (5, 5)]], "unexpected 'x' at character 17"),
    ("M 0 0 L 5 5,, 6 6", [[(0, 0), (5, 5)]], "unexpected ','"),
    ("M 0 0 L 5 5 Z 3 3", [[(0, 0), (5, 5), (0, 0)]], "number '3' after 'Z'"),
    ("M 0 0 A 1 1 0 2 1 5 5 L 9 9", [[(0, 0)]], "arc flag must be 0 or 1"),
    ("M 0 0 L 1. 5", [[(0, 0)]], "unexpected '.'"),
    ("M 0 0 L 5 5 M", [[(0, 0), (5, 5)]], "'M' has too few numbers"),
    ("M 0 0 H 3 4 V 2 L 1 1 ,", [[(0, 0), (3, 0), (4, 0), (4, 2), (1, 1)]], "unexpected ','"),
])
def test_path_data_is_drawn_up_to_its_first_error(d, drawn, error):
    geo, found = curves.path_data(d, 0.01)
    assert [p.tolist() for p, _ in geo] == [[list(map(float, q)) for q in s] for s in drawn]
    assert found is not None and error in found


def test_numbers_read_up_to_their_error():
    assert pathdata.numbers("1,2 3-4.5.5") == ([1, 2, 3, -4.5, 0.5], None)
    vals, error = pathdata.numbers("1 2 3 4 five 6")
    assert vals == [1, 2, 3, 4] and "unexpected 'f' at character 9" in error


def test_css_important_wins_over_the_style_attribute_and_transform_is_a_property():
    root = parse_svg_xml(b'<svg xmlns="http://www.w3.org/2000/svg"><style>'
                         b'.a { stroke: red !important; fill: blue; transform: rotate(90deg) }'
                         b'</style><path class="a" style="stroke: green; fill: yellow"/>'
                         b'</svg>')
    sheet = Stylesheet(root)
    _, own = cascade(root[1], "path", svgstyle.ROOT_STYLE, sheet)
    assert own["stroke"] == "red" and own["fill"] == "yellow"
    assert np.allclose(curves.parse_transform(own["transform"]), (0, 1, -1, 0, 0, 0))


@pytest.mark.parametrize("text", ["rotate(30)", "translate(10,5) scale(2)",
                                  "matrix(1 2 3 4 5 6)", "rotate(30 10 20)",
                                  "skewX(20) skewY(10)", "scale(2,3)", "translate(3)"])
def test_transforms_read_as_svgelements_reads_them(text):
    m = se.Matrix(text)
    assert np.allclose(curves.parse_transform(text), (m.a, m.b, m.c, m.d, m.e, m.f))


@pytest.mark.parametrize("text", ["matrix(1 2 3)", "translate(", "rotate(a)", "foo(1)",
                                  "scale(1)(", "rotate(1 2)"])
def test_bad_transforms_name_what_is_wrong(text):
    with pytest.raises(ValueError):
        curves.parse_transform(text)


# ---- the ReDoS input and its kind, and fuzzing -------------------------------------

def cpu(fn, *args) -> float:
    start = time.process_time()
    fn(*args)
    return time.process_time() - start


def bound(n: int) -> float:
    """CPU seconds an input of n characters may take: 20 µs a character (the parsers
    take ~1-3) and 50 ms to start; CPU time, so a loaded machine does not count."""
    return 0.05 + 2e-5 * n


@pytest.mark.parametrize("pairs", [6, 20, 2000])
def test_the_backtracking_path_of_issue_32_is_read_in_linear_time(pairs):
    d = "M0 0" + "L10.5 10.5" * pairs + "A1 1 0 0 1 2 2"
    took = cpu(curves.path_data, d, 0.01)
    assert took < bound(len(d)), took
    geo, error = curves.path_data(d, 0.01)
    assert error is None and len(geo[0][0]) > pairs


@pytest.mark.parametrize("tail", ["x", "!", ",", "e", ".", "A1 1 0 2"])
def test_long_runs_of_digits_and_separators_before_an_error_stay_linear(tail):
    for body in ("1" * 50_000, "1.1" * 20_000, " ,1" * 20_000, "-1e1" * 20_000,
                 "M" + "0" * 50_000):
        d = "M 0 0 L " + body + tail
        assert cpu(curves.path_data, d, 0.01) < bound(len(d))
        for parse in (pathdata.numbers, svgstyle.declarations, curves_transform):
            assert cpu(parse, body + tail) < bound(len(body))
        assert cpu(svgstyle_length, body + tail) < bound(len(body))
        assert cpu(Stylesheet, style_doc("a{" * 5000 + body + tail + "/*" * 5000)) < 0.5


def curves_transform(text: str) -> None:
    try:
        curves.parse_transform("rotate(" + text)
    except ValueError:
        pass


def svgstyle_length(text: str) -> None:
    try:
        svgstyle.length(text)
    except ValueError:
        pass
    svgstyle.url_id("url(#" + text)
    svgstyle.paint({"stroke": text}, "stroke")


def style_doc(css: str):
    return parse_svg_xml(f'<svg xmlns="http://www.w3.org/2000/svg"><style>{css}</style>'
                         '</svg>'.encode())


PATH_CHARS = st.sampled_from([*"MmLlHhVvZzCcSsQqTtAa0123456789.-+eE ,\t\n", "10.5 "])
EXAMPLES = int(os.environ.get("PLOTBRIDGE_FUZZ_EXAMPLES", "300"))


@settings(max_examples=EXAMPLES, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(parts=st.lists(PATH_CHARS, max_size=400), repeat=st.integers(1, 40))
def test_fuzzed_path_data_is_read_or_named_within_its_time_bound(parts, repeat):
    d = "".join(parts) * repeat
    took = cpu(curves.path_data, d, 0.05)
    assert took < bound(len(d)), (took, d[:200])
    geo, error = curves.path_data(d, 0.05)
    assert error is None or "character" in error or "numbers" in error or "moveto" in error \
        or "after" in error or "flag" in error, error
    assert all(p.ndim == 2 and p.shape[1] == 2 and len(p) >= 1 for p, _ in geo)
    vals, _ = pathdata.numbers(d)
    assert all(isinstance(v, float) for v in vals)


CSS_CHARS = st.sampled_from([*"{}:;!/*.#,() -%", "important", "stroke", "fill", "url(#a",
                             "rotate", "1", "2.5", "deg", "px", "a", "@media"])


@settings(max_examples=EXAMPLES, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(parts=st.lists(CSS_CHARS, max_size=300), repeat=st.integers(1, 30))
def test_fuzzed_styles_are_read_within_their_time_bound(parts, repeat):
    css = "".join(parts) * repeat
    start = time.process_time()
    sheet = Stylesheet(style_doc(css.replace("<", "").replace("&", "")))
    svgstyle.declarations(css)
    svgstyle_length(css)
    curves_transform(css)
    took = time.process_time() - start
    assert took < 2 * bound(len(css)), (took, css[:200])
    assert all(isinstance(k, str) for k in sheet.rules)
