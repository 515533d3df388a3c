"""Preview decimation, the resume preamble and the written files."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest
from plotbridge.importing.preview import PreviewBuilder
from plotbridge.importing.simplify import simplify
from plotbridge.resume import Mark, ResumePoint, locate, resume_preamble

from tests.fixtures.imports import program_lines, run_import


def test_simplify_keeps_shape_and_drops_collinear_points():
    line = np.c_[np.linspace(0, 10, 101), np.zeros(101)]
    assert simplify(line, 0.01).tolist() == [[0, 0], [10, 0]]
    zigzag = np.array([[0, 0], [1, 1], [2, 0], [3, 1], [4, 0]], dtype=float)
    assert len(simplify(zigzag, 0.5)) == 5
    # A spike back along the line must survive: distance to the segment, not the line.
    spike = np.array([[0, 0], [10, 0], [5, 0]], dtype=float)
    assert len(simplify(spike, 0.1)) == 3


def _rdp_reference(pts: np.ndarray, tol: float, fixed: list[int]) -> np.ndarray:
    """Ramer-Douglas-Peucker as simplify.c states it, a segment at a time in numpy."""
    keep = np.zeros(len(pts), bool)
    keep[fixed] = True
    at = np.flatnonzero(keep)
    todo = [(int(a), int(b)) for a, b in itertools.pairwise(at) if b > a + 1]
    while todo:
        a, b = todo.pop()
        d = pts[b] - pts[a]
        dd = d[0] * d[0] + d[1] * d[1]
        r = pts[a + 1:b] - pts[a]
        t = np.clip((r[:, 0] * d[0] + r[:, 1] * d[1]) / (dd if dd > 0 else 1.0), 0.0, 1.0)
        o = r - t[:, None] * d
        d2 = o[:, 0] * o[:, 0] + o[:, 1] * o[:, 1]
        if np.isnan(d2).any() or not d2.max() > tol * tol:
            continue
        k = a + 1 + int(np.argmax(d2))
        keep[k] = True
        todo += [(a, k)] * (k > a + 1) + [(k, b)] * (b > k + 1)
    return keep


@pytest.mark.parametrize("seed", range(6))
def test_simplify_mask_keeps_the_points_the_algorithm_names(seed):
    # Ties (repeated and grid points: the first farthest is kept), zero-length
    # segments, NaN, and every length around the two-at-a-time loop.
    from plotbridge.importing.simplify import simplify_mask
    rng = np.random.default_rng(seed)
    for n in [*range(2, 14), 200, 1000]:
        pts = np.cumsum(rng.choice([-1.0, 0.0, 1.0], size=(n, 2)), axis=0)
        if seed % 2:
            pts = np.cumsum(rng.normal(size=(n, 2)), axis=0)
        if seed == 4 and n > 5:
            pts[n // 2] = np.nan
        fixed = sorted({0, n - 1, *rng.integers(0, n, size=n // 50).tolist()})
        for tol in (0.0, 0.3, 1.0, 4.0):
            got = simplify_mask(pts, tol, np.array(fixed))
            assert got.tolist() == _rdp_reference(pts, tol, fixed).tolist()


def test_preview_is_decimated_within_budget_and_tolerance():
    t = np.linspace(0, 40 * math.pi, 100_000)
    spiral = np.c_[100 + t * np.cos(t) / 2, 100 + t * np.sin(t) / 2]
    pb = PreviewBuilder(max_points=5_000)
    for (x0, y0), (x1, y1) in itertools.pairwise(spiral):
        pb.draw(x0, y0, x1, y1)
    body = pb.finish({})
    pts = [p for s in body["strokes"] for p in s]
    assert len(pts) <= 5_000
    # Every original point is within the final tolerance of the preview polyline.
    kept = np.asarray(body["strokes"][0])
    sample = spiral[::997]
    for p in sample:
        d = kept[1:] - kept[:-1]
        rel = p - kept[:-1]
        tt = np.clip(np.einsum("ij,ij->i", rel, d) / np.einsum("ij,ij->i", d, d), 0, 1)
        dist = np.min(np.hypot(*(rel - tt[:, None] * d).T))
        assert dist <= pb.tolerance + 1e-3


def test_preview_file_matches_program(tmp_path):
    r = run_import(tmp_path, "G0 X10 Y10\nM3\nG1 X20 F600\nM5\nG0 X30 Y30\nM3\nG1 X40 F600\n")
    body = json.loads(r.preview_path.read_text())
    assert body["strokes"] == [[[10, 10], [20, 10]], [[30, 30], [40, 30]]]
    assert body["travel"] == [[[0, 0], [10, 10]], [[20, 10], [30, 30]]]
    assert body["bounds"] == r.bounds


def test_resume_preamble_restores_position_and_pen(tmp_path):
    r = run_import(tmp_path, "G0 X10 Y10\nM3\nG1 X20 F600\nG1 Y20\nM5\nG0 X50 Y50\n")
    lines = program_lines(r)
    assert lines[6] == "G1 X20.000 Y20.000 F600"      # program line 7
    assert resume_preamble(r.program_path, ResumePoint(7)) == (7, [
        "M5", "G21", "G90", "G0 X20.0000 Y10.0000", "M3"])
    assert resume_preamble(r.program_path, ResumePoint(9)) == (9, [
        "M5", "G21", "G90", "G0 X20.0000 Y20.0000"])
    assert resume_preamble(r.program_path, ResumePoint(1)) == (1, [
        "M5", "G21", "G90", "G0 X0.0000 Y0.0000"])
    # where the pen stopped on line 7: the pen goes down there, line 7 draws the rest
    assert resume_preamble(r.program_path, ResumePoint(7, (20.0, 13.25))) == (7, [
        "M5", "G21", "G90", "G0 X20.0000 Y13.2500", "M3"])


def test_locate_finds_the_executing_line_and_point(tmp_path):
    r = run_import(tmp_path, "G0 X10 Y10\nM3\nG1 X20 F600\nG1 Y20\nG1 X10\nM5\n")
    lines = program_lines(r)
    assert lines[5:8] == ["G1 X20.000 Y10.000 F600", "G1 X20.000 Y20.000 F600",
                          "G1 X10.000 Y20.000 F600"]  # program lines 6, 7, 8
    path = r.program_path
    # the reported point lies on line 7 (the window is lines 3..8)
    assert locate(path, Mark(3, 8, 20.0, 13.25)) == ResumePoint(7, (20.0, 13.25))
    assert locate(path, Mark(3, 8, 15.0, 20.0)) == ResumePoint(8, (15.0, 20.0))
    # on a pen-up move: the travel goes on from there, the pen stays up
    assert locate(path, Mark(1, 8, 5.0, 5.0)) == ResumePoint(4, (5.0, 5.0))
    # nowhere on the window's moves: the conservative first line
    assert locate(path, Mark(6, 8, 50.0, 50.0)) == ResumePoint(6)
    # a corner shared by two lines: the earlier (a zero-length rest, nothing skipped)
    assert locate(path, Mark(3, 8, 20.0, 20.0)) == ResumePoint(7, (20.0, 20.0))
    # stock GRBL's Ln: may name a line its steps have not reached: the pen's own move
    assert locate(path, Mark(8, 8, 20.0, 13.25)) == ResumePoint(7, (20.0, 13.25))
    assert locate(path, Mark(8, 8, 20.0, 13.25, (15.0, 20.0))) == ResumePoint(8, (15.0, 20.0))


def test_locate_looks_back_a_few_moves_only(tmp_path):
    strokes = "".join(f"G1 X{k} F600\n" for k in range(1, 31))
    r = run_import(tmp_path, f"G0 X0 Y0\nM3\n{strokes}M5\n")
    path = r.program_path
    line = {float(t.split()[1][1:]): n for n, t in enumerate(program_lines(r), 1)
            if t.startswith("G1")}  # the line that ends at x
    assert locate(path, Mark(line[20], line[20], 12.5, 0.0)) == ResumePoint(line[13], (12.5, 0.0))
    # further back than a segment buffer runs ahead: not taken
    assert locate(path, Mark(line[25], line[25], 12.5, 0.0)) == ResumePoint(line[25])


def test_resume_after_an_arc(tmp_path):
    r = run_import(tmp_path, "G0 X10 Y10\nM3\nG2 X30 Y10 I10 J0 F600\nG1 X40 F600\n")
    assert resume_preamble(r.program_path, ResumePoint(7))[1][-2:] == [
        "G0 X30.0000 Y10.0000", "M3"]
    # a stop on the arc resumes on the arc (tests/unit/test_resume_point.py)
    assert locate(r.program_path, Mark(5, 8, 20.0, 20.0)) == ResumePoint(6, (20.0, 20.0))


def test_normalized_program_is_plain(tmp_path):
    r = run_import(tmp_path, "; x\nG21 G90 G17\nG0 X1 Y1 Z5\nG1 Z-1 F100\nG1 X2.12345 F1000\n"
                             "G0 Z5\nM2\n")
    text = r.program_path.read_text()
    assert text.endswith("M5\n") and "\n\n" not in text
    for line in text.splitlines():
        head = line.split()[0]
        assert head in {"G21", "G90", "G0", "G1", "G2", "G3", "G4", "M3", "M5"}
        if head in ("G1", "G2", "G3"):
            assert " F" in line
        if head == "G0":
            assert " F" not in line
    assert "G1 X2.123 Y1.000 F1000" in text


def test_estimate_counts_pen_settle(tmp_path):
    one = run_import(tmp_path, "G0 X10 Y10\nM3\nG1 X20 F600\nM5\n")
    two = run_import(tmp_path, "G0 X10 Y10\nM3\nG1 X15 F600\nM5\nM3\nG1 X20 F600\nM5\n")
    # Two more pen moves (0.15 s each) and a stop in the middle of the line.
    assert two.estimate_s > one.estimate_s + 0.3
    assert one.timeline[-1] == (one.lines_total, pytest.approx(one.estimate_s))


def test_results_and_failures_cross_process_boundaries(tmp_path):
    import pickle

    from plotbridge.importing import ImportFailed

    r = run_import(tmp_path, "G0 X10 Y10\nM3\nG1 X20 F600\n")
    assert pickle.loads(pickle.dumps(r)) == r
    e = pickle.loads(pickle.dumps(ImportFailed(422, [{"line": 3, "message": "bad"}])))
    assert (e.status, e.errors) == (422, [{"line": 3, "message": "bad"}])
