"""The importer's fast paths give what the general paths give, byte for byte: G-code's
common lines (native/gcodescan.c, read a chunk at a time, written in bulk by
ProgramWriter.moves through native/movelines.c) against every line through the general
parser and each move written alone; the preview's strokes written by
native/previewjson.c against json.dumps. Both ways go through penplace.py (pen-downs
with no move dropped, the first pen-down placed with the drawing)."""

from __future__ import annotations

import json
import math
import random
import re
from pathlib import Path

import numpy as np
import pytest
from plotbridge.importing import ImportFailed, ImportOptions, MachineProfile
from plotbridge.importing.detect import line_chunks
from plotbridge.importing.gcode import read_ops
from plotbridge.importing.models import ErrorLog
from plotbridge.importing.ops import PATH, single_moves
from plotbridge.importing.penplace import placed_pens
from plotbridge.importing.pipeline import write_program
from plotbridge.importing.placement import Transform
from plotbridge.importing.preview import PreviewBuilder
from plotbridge.native import movelines
from plotbridge.native.gcodescan import LINE, OTHER, PEN_DOWN, PEN_UP, RAPID, scan
from plotbridge.native.previewjson import strokes_json
from plotbridge.native.textcheck import first_control

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
PROFILE = MachineProfile(width=300, height=220)


def _write(src: Path, dest: Path, options: ImportOptions, fast: bool, transform: Transform,
           chunk: int) -> tuple:
    """(program, preview, result or the errors) of one way of importing."""
    errors = ErrorLog()

    def ops():
        chunks = line_chunks(src, "utf-8", chunk)
        if fast:
            return placed_pens(read_ops(chunks, options, errors), errors)
        return placed_pens(single_moves(read_ops(chunks, options, errors, fast=False)), errors)

    try:
        r = write_program(ops, "gcode", dest, transform, PROFILE, errors)
    except ImportFailed as e:
        return None, None, (e.status, e.errors)
    result = (r.lines_total, r.estimate_s, r.bounds, r.stats, r.timeline, r.layers, r.warnings)
    return r.program_path.read_bytes(), r.preview_path.read_bytes(), result


def assert_same_import(src: Path, tmp_path: Path, options: ImportOptions,
                       transform: Transform | None = None, chunk: int = 1 << 18) -> None:
    transform = transform or Transform()
    fast = _write(src, tmp_path / "fast", options, True, transform, chunk)
    general = _write(src, tmp_path / "general", options, False, transform, chunk)
    assert fast[2] == general[2]
    assert fast[0] == general[0]
    assert fast[1] == general[1]


def test_scan_reads_common_lines_and_leaves_the_rest():
    text = ("G1 X1.5 Y-2 F3000\ng0x.5y+7\n  G01\tX 1. Y 2 ; a note\nG1 X1 Y2 ;(no)\n"
            "G1 X1e3 Y2\nG1 Y2 X1\nN5 G1 X1 Y2\nG10 X1 Y2\nG1 X1 Y2 F\n\nG1 X1 Y2 ; é\n"
            f"G1 X1 Y2 ;{'x' * 300}\n")
    lines = scan(text, 256)
    kind, x, y, f = lines.kind, lines.x, lines.y, lines.f
    assert kind.tolist() == [LINE, RAPID, LINE] + [OTHER] * 9
    assert x[:3].tolist() == [1.5, 0.5, 1.0] and y[:3].tolist() == [-2.0, 7.0, 2.0]
    assert f[0] == 3000 and np.isnan(f[1:3]).all()
    assert lines.feed[:3].tolist() == [3000.0] * 3     # the run's last F
    assert [lines.line(k) for k in (3, 9, 10)] == ["G1 X1 Y2 ;(no)", "", "G1 X1 Y2 ; é"]


def test_scan_leaves_feeds_that_are_not_positive_to_the_general_parser():
    lines = scan("G1 X1 Y2 F100\nG1 X1 Y2 F0\nG1 X1 Y2 F-5\nG1 X1 Y2\nG1 X1 Y2 F.5\n", 256)
    assert lines.kind.tolist() == [LINE, OTHER, OTHER, LINE, LINE]
    assert np.isnan(lines.feed[3]) and lines.feed[4] == 0.5    # a run restarts after one


def test_scan_reads_pen_lines_and_keeps_the_feed_across_them():
    lines = scan("G1 X1 Y2 F100\nM3\nm05 ; up\nM 004\nM3 S1\nM30\nM3.0\nM3 (x)\nM5\n"
                 "G1 X2 Y2\n", 256)
    assert lines.kind.tolist() == [LINE, PEN_DOWN, PEN_UP, PEN_DOWN, OTHER, OTHER, OTHER,
                                   OTHER, PEN_UP, LINE]
    assert lines.feed[:4].tolist() == [100.0] * 4 and np.isnan(lines.feed[8])


def test_control_bytes_found_natively_are_those_text_files_do_not_hold():
    text = {9, 10, 12, 13, 26}
    for b in range(256):
        for at in range(0, 23, 3):     # in the words read 8 bytes at a time and after
            data = bytearray(b"G1 X1\nY2 \xe9\r\n;\tab\x1a\x0cc\xff\n"[:at] + b"x" * (23 - at))
            data[at] = b
            bad = b < 32 and b not in text
            assert first_control(bytes(data)) == (at if bad else -1)
            assert first_control(bytes(data) + b"\x00") == (at if bad else len(data))
    assert first_control(b"") == -1


@pytest.mark.parametrize("data", [
    b"G21\nG1 X1 Y2 F600 ; \xc3\xa9t\xc3\xa9\n" * 40 + b"M5",      # LF, UTF-8, no last LF
    b"G21\r\nG1 X1 Y2 F600\r\n" * 40,                             # CRLF from the start
    b"G1 X1 Y2 F600\n" * 40 + b"G1 X2 Y2\r\nM5\rM3\r\n" + b"G1 X3 Y3\n" * 40,  # CR later
    b"\xef\xbb\xbfG1 X1 Y2 F600\n\n" * 30,                          # a BOM, blank lines
])
@pytest.mark.parametrize("size", [7, 64, 1 << 18])
def test_line_chunks_give_the_text_read_with_universal_newlines(tmp_path, data, size):
    # A UTF-8 file's chunks are its bytes until one holds a CR, then text read as before.
    src = tmp_path / "a.gcode"
    src.write_bytes(data)
    text = src.read_text(encoding="utf-8")
    text += "" if text.endswith("\n") else "\n"
    got = []
    for chunk in line_chunks(src, "utf-8", size):
        chunk = chunk.decode("utf-8") if isinstance(chunk, bytes) else chunk
        assert chunk.endswith("\n")
        got.append(chunk)
    assert "".join(got) == text
    if b"\r" not in data:
        assert all(isinstance(c, bytes) for c in line_chunks(src, "utf-8", size))


def test_a_crlf_file_imports_as_its_lf_twin(tmp_path):
    lines = [f"G1 X{k % 7 + 1} Y{k % 5 + 1} F600" for k in range(300)]
    text = "G21\nM3\n" + "\n".join(lines) + "\nM5\n"
    (tmp_path / "lf.gcode").write_bytes(text.encode())
    (tmp_path / "crlf.gcode").write_bytes(text.replace("\n", "\r\n").encode())
    lf = _write(tmp_path / "lf.gcode", tmp_path / "lf", ImportOptions(), True, Transform(), 100)
    crlf = _write(tmp_path / "crlf.gcode", tmp_path / "crlf", ImportOptions(), True,
                  Transform(), 100)
    assert lf == crlf


def test_strokes_are_read_as_path_ops_a_chunk_at_a_time(tmp_path):
    src = tmp_path / "s.gcode"
    src.write_text("G21\n" + "G0 X1 Y1\nM3\nG1 X2 Y2 F600\nG1 X3 Y1\nM5\n" * 50)
    ops = list(read_ops(line_chunks(src, "utf-8"), ImportOptions(), ErrorLog()))
    assert [op[0] for op in ops] == [PATH]      # G21 is read alone and changes nothing
    assert len(list(single_moves(ops))) == 250


@pytest.mark.parametrize("name", sorted(p.name for p in (FIXTURES / "gcode").glob("*.gcode")))
def test_gcode_fixtures_import_the_same_on_both_paths(name, tmp_path):
    assert_same_import(FIXTURES / "gcode" / name, tmp_path, ImportOptions())


def _corpus(rng: random.Random, lines: int) -> str:
    """G-code mixing the common lines with everything that leaves the fast path."""
    out = []
    x, y = 100.0, 100.0
    for _ in range(lines):
        r = rng.random()
        x = min(max(x + rng.uniform(-3, 3), -2), 305)
        y = min(max(y + rng.uniform(-3, 3), -2), 222)
        g = rng.choice(["G1", "G01", "g1", "G0", "G00"])
        f = rng.choice(["", "", "", " F3000", " F1500.55", "F600", " F0"])
        sep = rng.choice([" ", "", "\t"])
        tail = rng.choice(["", "", " ; seg", ";", " (c)", " ;(x)", " ; a*b"])
        if r < 0.75:
            out.append(f"{g}{sep}X{x:.{rng.randint(0, 4)}f}{sep}Y{y:.3f}{f}{tail}")
        elif r < 0.80:
            out.append(rng.choice(["M3", "M5", "M03 S1", "M05"]))
        elif r < 0.83:
            out.append(rng.choice(["G91", "G90", "G20", "G21"]))
        elif r < 0.86:
            out.append(f"N{rng.randint(1, 99)} G1 X{x:.3f} Y{y:.3f}")
        elif r < 0.88:
            out.append(f"G92 X{rng.uniform(-5, 5):.2f} Y{rng.uniform(-5, 5):.2f}")
        elif r < 0.90:
            out.append(f"G2 X{x:.3f} Y{y:.3f} I1 J0")
        elif r < 0.92:
            out.append(rng.choice(["", "   ", "%", "; comment only", "(setup)", "M0 change"]))
        elif r < 0.94:
            out.append(f"G1 X{x:.3f} Y{y:.3f} Z{rng.choice(['-1', '2'])}")
        elif r < 0.96:
            out.append(f"G1 X-{x:.3f} Y{y:.3f}")
        else:
            out.append(f"G1 X{x:.3f} Y{y:.3f} ; {'long comment ' * rng.randint(10, 30)}")
    return "\n".join(out) + rng.choice(["\n", ""])


@pytest.mark.parametrize("seed", range(12))
def test_generated_gcode_imports_the_same_on_both_paths(seed, tmp_path):
    rng = random.Random(seed)
    src = tmp_path / "gen.gcode"
    src.write_text(_corpus(rng, 1500))
    dialect = ["auto", "m3", "none", "laser", "z"][seed % 5]
    transform = [Transform(), Transform(scale=0.5, quarter=1, tx=150.0, ty=3.0)][seed % 2]
    assert_same_import(src, tmp_path, ImportOptions(pen_dialect=dialect), transform,
                       chunk=rng.choice([64, 1000, 1 << 18]))


def test_generated_gcode_that_stays_on_the_page_imports_the_same(tmp_path):
    # The errors above stop most generated files; this one is accepted.
    rng = random.Random(99)
    lines = ["G21", "G90", "G0 X10 Y10", "M3"]
    x, y = 10.0, 10.0
    for k in range(20000):
        x = min(max(x + rng.uniform(-1, 1), 1), 299)
        y = min(max(y + rng.uniform(-1, 1), 1), 219)
        lines.append(f"G1 X{x:.4f} Y{y:.4f}" + (f" F{rng.choice((1500, 3000))}" if k % 7 == 0
                                                 else "") + (" ; s" if k % 3 else ""))
        if k % 500 == 499:
            lines += ["M5", f"G0 X{x + 1:.3f} Y{y:.3f}", "M3"]
    src = tmp_path / "walk.gcode"
    src.write_text("\n".join(lines) + "\nM5\n")
    assert_same_import(src, tmp_path, ImportOptions(), chunk=4096)
    program, _, result = _write(src, tmp_path / "again", ImportOptions(), True, Transform(),
                                1 << 18)
    assert program is not None and result[0] > 20000


def test_preview_strokes_written_natively_as_json_dumps_writes_them(tmp_path):
    rng = np.random.default_rng(5)
    edge = [0.0, -0.0, -0.0004, 0.0005, 0.0015, 0.0025, 2.675, 1e11 + 0.0625, 299.9995,
            -12.3456, 1e-9, 100.1, 7.0]
    strokes = [np.array(edge, float).reshape(-1, 2) if len(edge) % 2 == 0 else
               np.array(edge[:-1], float).reshape(-1, 2)]
    strokes += [rng.uniform(-5, 400, (int(rng.integers(1, 50)), 2)) for _ in range(200)]
    strokes += [np.round(rng.uniform(0, 300, (30, 2)), int(rng.integers(0, 4)))
                for _ in range(50)]
    pb = PreviewBuilder()
    for s in strokes:
        pb.draw_path(s)
        pb.end_stroke()
        pb.move(1.0, 2.0, 3.00049, 4.0)
    bounds = {"min_x": 0.0, "min_y": -0.0, "max_x": 1.5, "max_y": 2.0}
    pb.write(tmp_path / "p.json", bounds)
    assert strokes_json(pb.strokes) is not None
    assert (tmp_path / "p.json").read_text() == json.dumps(pb.finish(bounds),
                                                           separators=(",", ":"))
    assert strokes_json([np.array([[1e13, 0.0]])]) is None     # left to json.dumps


def _python_lines(x, y, feeds, start, feed_text) -> str:
    """What ProgramWriter.move writes for each point, repeats skipped."""
    out, last = [], start
    for a, b, f in zip(x.tolist(), y.tolist(), feeds.tolist(), strict=True):
        at = (float(f"{a:.3f}"), float(f"{b:.3f}"))
        if at != last:
            out.append(f"G0 X{a:.3f} Y{b:.3f}\n" if f != f else
                       f"G1 X{a:.3f} Y{b:.3f} F{feed_text(f)}\n")
        last = at
    return "".join(out)


START = movelines.State(0.0, 0.0, False, 0, 0, 0.0, 0.0, [math.inf, math.inf, -math.inf, -math.inf])


def test_move_lines_round_as_python_formats_and_keep_feed_texts(monkeypatch):
    monkeypatch.setattr(movelines, "FEEDS_MAX", 8)    # the texts start afresh often
    rng = np.random.default_rng(11)
    texts = []

    def feed_text(f: float) -> str:
        texts.append(f)
        return f"{round(f, 1):g}"

    run = movelines.MoveLines((-1.0, -1.0, 1e6, 1e6), feed_text, 0, 1)
    # exact halves of the third decimal (ties to even), values rounding to -0.000,
    # long random ones, repeats
    ties = np.array([k / 16 for k in range(-8, 400)] + [k / 2048 for k in range(-2, 3000, 7)])
    for trial in range(150):
        n = int(rng.integers(1, 60))
        x = rng.choice(np.r_[ties, rng.uniform(-0.9, 500, 50), -0.0004, -0.0], n)
        y = rng.choice(np.r_[ties, rng.uniform(0, 300, 50)], n)
        if trial % 3 == 0:
            x[1::2], y[1::2] = x[:-1:2], y[:-1:2]
        feeds = rng.choice(np.r_[rng.uniform(1, 9000, 20), [np.nan, 1500.0]], n)
        run.load(None, x, y, feeds)
        lines = run.run(0, START, True)
        assert lines.stop == n
        text = lines.text.decode("ascii")
        assert text == _python_lines(x, y, feeds, (0.0, 0.0), feed_text)
        assert [str(v) for v in lines.xy.ravel()] == [
            str(float(t)) for t in re.findall(r"[XY](\S+)", text)]
    run.load(None, np.array([5.0, 2e6, 6.0]), np.zeros(3), np.ones(3))
    lines = run.run(0, START, True)      # it stops at the point outside the area
    assert lines.stop == 1 and lines.text == b"G1 X5.000 Y0.000 F1\n"
    assert lines.state.x == 5.0 and lines.state.line == 1
    assert run.run(2, lines.state, True).text == b"G1 X6.000 Y0.000 F1\n"


def test_move_lines_write_pen_changes_and_stop_at_a_pen_down_left_to_the_writer():
    run = movelines.MoveLines((-1.0, -1.0, 300.0, 300.0), lambda f: f"{f:g}", 0, 1, 6, 0.25)
    kinds = np.array([RAPID, PEN_DOWN, LINE, LINE, PEN_DOWN, OTHER, PEN_UP, RAPID, PEN_DOWN],
                     np.uint8)
    x = np.array([1.0, 0, 2, 2.0004, 0, 0, 0, 5, 0])
    run.load(kinds, x, x, np.where(kinds == LINE, 600.0, np.nan))
    lines = run.run(0, START, True)
    assert lines.text == (b"G0 X1.000 Y1.000\nM3\nG1 X2.000 Y2.000 F600\nM5\n"
                          b"G0 X5.000 Y5.000\nM3\n")
    assert lines.stop == len(kinds)
    assert lines.kind.tolist() == [0, 6, 1, 6, 0, 6]      # pen changes: dwells of 0.25 s
    assert lines.x32[1] == np.float32(0.25) and lines.nbytes.tolist() == [17, 3, 22, 3, 17, 3]
    assert lines.events[0] == [movelines.EV_TRAVEL, movelines.EV_DOWN, movelines.EV_DRAW,
                               movelines.EV_UP, movelines.EV_TRAVEL, movelines.EV_DOWN]
    s = lines.state
    assert (s.x, s.down, s.line, s.lifts, s.bounds) == (5.0, True, 6, 1, [1.0, 1.0, 5.0, 5.0])
    assert s.down_mm == math.sqrt(2) and s.travel_mm == math.sqrt(2) + math.sqrt(18)
    lines = run.run(0, START, False)    # the writer starts its first layer itself
    assert lines.stop == 1 and lines.text == b"G0 X1.000 Y1.000\n"
