"""G-code import: dialects, units, relative moves, arcs and validation."""

from __future__ import annotations

import re
import tempfile
import threading
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from plotbridge.importing import ImportFailed, ImportOptions, MachineProfile
from plotbridge.importing.gcode import read_ops
from plotbridge.importing.models import ErrorLog
from plotbridge.importing.ops import MOVE, PEN, single_moves

from tests.fixtures.imports import drawn_strokes, program_lines, run_import


def test_m3_dialect_is_normalized(tmp_path):
    r = run_import(tmp_path, "G21\nG90\nG0 X10 Y10\nM3\nG1 X20 F1200\nY20\nM5\n")
    assert program_lines(r) == [
        "G21", "G90", "M5", "G0 X10.000 Y10.000", "M3",
        "G1 X20.000 Y10.000 F1200", "G1 X20.000 Y20.000 F1200", "M5"]
    assert r.lines_total == 8
    assert r.format == "gcode"
    assert r.bounds == {"min_x": 10.0, "min_y": 10.0, "max_x": 20.0, "max_y": 20.0}
    assert r.stats["pen_down_mm"] == pytest.approx(20.0)
    assert r.stats["pen_lifts"] == 1


def test_comments_line_numbers_and_checksums(tmp_path):
    body = "N3 G1 X5 Y5 F600"
    check = 0
    for ch in body.encode():
        check ^= ch
    text = f"(header) ; more\nN1 G0 X1 Y1 (go)\nN2 M3 ; down\n{body}*{check}\n%\n"
    r = run_import(tmp_path, text)
    assert program_lines(r)[3:6] == ["G0 X1.000 Y1.000", "M3", "G1 X5.000 Y5.000 F600"]


def test_bad_checksum_is_reported_with_its_line(tmp_path):
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, "M3\nG1 X5 Y5 F600*1\n")
    assert e.value.status == 422
    assert e.value.errors[0]["line"] == 2
    assert "checksum" in e.value.errors[0]["message"]


def test_a_checksum_of_digits_int_refuses_is_malformed(tmp_path):
    with pytest.raises(ImportFailed) as e:  # "²".isdigit() is true, int("²") fails
        run_import(tmp_path, "M3\nG1 X5 Y5 F600*\u00b2\n")
    assert e.value.errors[0] == {"line": 2, "message": "malformed checksum '*\u00b2'"}


@pytest.mark.parametrize(("text", "options"), [
    ("G0 Z5\nG0 X10 Y10\nG1 Z-1 F300\nG1 X20 F600\nG0 Z5\n", {}),
    ("G0 Z5\nG0 X10 Y10\nG1 Z0.5 F300\nG1 X20 F600\nG0 Z5\n", {"pen_dialect": "z",
                                                               "z_threshold": 1.0}),
    ("M300 S50\nG0 X10 Y10\nM300 S30\nG1 X20 F600\nM300 S50\n", {}),
    ("G0 Z90\nG0 X10 Y10\nG0 Z30\nG1 X20 F600\nG0 Z90\n", {"pen_dialect": "servo-z",
                                                          "servo_down_angle": 30}),
    ("M5\nG0 X10 Y10\nM3 S1000\nG1 X20 F600\nM5\n", {"pen_dialect": "m3"}),
])
def test_pen_dialects_draw_the_same_line(tmp_path, text, options):
    r = run_import(tmp_path, text, **options)
    assert drawn_strokes(program_lines(r)) == [[(10.0, 10.0), (20.0, 10.0)]]


def test_inches_and_relative_moves_become_absolute_mm(tmp_path):
    r = run_import(tmp_path, "G20\nG0 X1 Y1\nM3\nG91\nG1 X1 F10\nY0.5\nG90 G21\nG1 X10 Y10\n")
    lines = program_lines(r)
    assert "G1 X50.800 Y25.400 F254" in lines
    assert "G1 X50.800 Y38.100 F254" in lines
    assert lines[-2] == "G1 X10.000 Y10.000 F254"


def test_arcs_are_kept_and_radius_form_converted(tmp_path):
    r = run_import(tmp_path, "G0 X10 Y10\nM3\nG2 X30 Y10 I10 J0 F600\nG3 X50 Y10 R10\n")
    lines = program_lines(r)
    assert "G2 X30.000 Y10.000 I10.000 J0.000 F600" in lines
    assert "G3 X50.000 Y10.000 I10.000 J0.000 F600" in lines
    # The clockwise half circle from (10,10) to (30,10) about (20,10) rises to y=20.
    assert r.bounds["max_y"] == pytest.approx(20.0)
    assert r.bounds["min_y"] == pytest.approx(0.0)


def test_all_errors_reported_with_line_numbers(tmp_path):
    text = "\n".join([
        "G0 X10 Y10",
        "M3",
        "G1 X20 F0",                    # 3: feed rate not positive
        "Q1",                           # 4: unsupported word
        "G1 X500 Y10 F100",             # 5: outside the work area
        "G2 X30 Y10 I3 J0",             # 6: radius 3 at the start, 7 at the end
        "G38.2 X1",                     # 7: unsupported command
        "G1 X1 Y$",                     # 8: unparseable
        "G1 X15 Y15",
    ])
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, text)
    assert e.value.status == 422
    lines = {err["line"]: err["message"] for err in e.value.errors}
    assert set(lines) == {3, 4, 5, 6, 7, 8}
    assert "feed" in lines[3]
    assert "Q1" in lines[4]
    assert "outside the work area" in lines[5]
    assert "radius" in lines[6]
    assert "G38.2" in lines[7]
    assert not (tmp_path / "out" / "program.gcode").exists()
    assert list((tmp_path / "out").iterdir()) == []


def test_arc_radius_tolerance_is_grbls(tmp_path):
    # 0.004 mm off is within 0.005 mm: accepted. 0.3 mm off on r=100 is over 0.1%: refused.
    run_import(tmp_path, "G0 X10 Y100\nM3\nG2 X210 Y100.004 I100 J0 F600\n")
    with pytest.raises(ImportFailed):
        run_import(tmp_path, "G0 X10 Y100\nM3\nG2 X210.3 Y100 I100 J0 F600\n")


def test_error_list_is_capped(tmp_path):
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, "M3\n" + "G1 X1 Y1 Q7\n" * 500)
    assert len(e.value.errors) == 100
    assert "more errors" in e.value.errors[-1]["message"]


def test_program_outside_a_smaller_machine_is_refused(tmp_path):
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, "G0 X10 Y10\nM3\nG1 X150 F600\n",
                   profile=MachineProfile(width=100, height=100))
    assert e.value.errors[0]["line"] == 3


def test_dwell_is_kept_and_timed(tmp_path):
    plain = run_import(tmp_path, "G0 X10 Y10\nM3\nG1 X20 F600\nM5\n")
    dwell = run_import(tmp_path, "G0 X10 Y10\nM3\nG4 P1.5\nG1 X20 F600\nM5\n")
    assert "G4 P1.500" in program_lines(dwell)
    # + the G4 line's own transfer and parse time
    assert dwell.estimate_s == pytest.approx(plain.estimate_s + 1.5, abs=5e-3)


def test_optimize_is_opt_in_for_gcode(tmp_path):
    text = ("G0 X10 Y10\nM3\nG1 X20 F600\nM5\nG0 X100 Y100\nM3\nG1 X110 F600\nM5\n"
            "G0 X20 Y10\nM3\nG1 X30 F600\nM5\n")
    plain = run_import(tmp_path, text)
    assert plain.stats["pen_lifts"] == 3
    opt = run_import(tmp_path, text, optimize=True)
    assert opt.stats["pen_lifts"] == 2       # the two strokes meeting at (20,10) merge
    assert opt.stats["travel_after_mm"] < opt.stats["travel_before_mm"]
    assert opt.stats["pen_down_mm"] == pytest.approx(plain.stats["pen_down_mm"])


def test_nothing_to_draw_is_refused(tmp_path):
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, "G0 X10 Y10\nG0 X20 Y20\n")
    assert "nothing to draw" in e.value.errors[0]["message"]


@pytest.mark.parametrize("line", [
    "G2 X10 Y10 I99999999 J0 F100",          # full circle of enormous radius
    "G1 X999999999999999999999999999 F100",
    "G3 X20 Y10 R99999999999999999999999999999999999999999999999999999999999999 F100",
])
def test_absurd_numbers_are_refused_quickly(tmp_path, line):
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, f"G0 X10 Y10\nM3\n{line}\nG1 X20 Y20\n")
    assert e.value.errors[0]["line"] == 3


def test_utf16_and_binary_get_clear_messages(tmp_path):
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, "G0 X1 Y1\n".encode("utf-16"))
    assert e.value.status == 415
    assert "UTF-16" in e.value.errors[0]["message"]


def test_auto_dialect_treats_m3_as_spindle_when_z_moves(tmp_path):
    # gcodetools style: M3 starts the spindle, Z lifts and lowers the tool.
    text = ("%\n(Header)\nM3\nG21\nG00 Z5.000000\nG00 X10 Y10\nG01 Z-0.125 F100.0\n"
            "G01 X20 Y10 F400\nG00 Z5.000000\nG00 X50 Y50\nG01 Z-0.125 F100\nG01 X60 Y50\n"
            "G00 Z5\nM5\nM2\n")
    r = run_import(tmp_path, text)
    assert drawn_strokes(program_lines(r)) == [[(10.0, 10.0), (20.0, 10.0)],
                                               [(50.0, 50.0), (60.0, 50.0)]]


def test_auto_dialect_ignores_a_lone_z_in_m3_files(tmp_path):
    r = run_import(tmp_path, "G0 Z0\nG0 X10 Y10\nM3\nG1 X20 F600\nM5\nG0 X30 Y30\n")
    assert drawn_strokes(program_lines(r)) == [[(10.0, 10.0), (20.0, 10.0)]]


gcode_word = st.sampled_from([*"GMXYZIJRFPSNT*();%", "G0", "G1", "G2", "G3", "G91", "M3", "M5",
                              "M300", " ", "-", ".", "1", "nan", "inf", "\t", "\xe9"])
gcode_text = st.lists(st.lists(st.one_of(gcode_word, st.floats(-500, 500).map(str)),
                               max_size=8).map("".join), max_size=30).map("\n".join)


@settings(max_examples=200, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(gcode_text)
def test_any_text_imports_or_fails_cleanly(tmp_path, text):
    example_dir = Path(tempfile.mkdtemp(dir=tmp_path))  # tmp_path is shared by all examples
    try:
        r = run_import(example_dir, text or "\n")
    except ImportFailed as e:
        assert e.status in (415, 422)
        assert 1 <= len(e.errors) <= 100
        assert all(set(err) == {"line", "message"} for err in e.errors)
        assert not (example_dir / "out" / "program.gcode").exists()
    else:
        assert r.lines_total == len(program_lines(r))


def _ops_and_errors(lines: list[str], options: ImportOptions) -> tuple[list, list]:
    errors = ErrorLog()
    ops = list(single_moves(read_ops(["".join(f"{ln}\n" for ln in lines)], options,
                                     errors)))
    return ops, errors.errors


_number = st.sampled_from(["10", "10.", ".5", "-3.25", "+7", "250.125", "0", "1e3", ""])
_line = st.builds(
    lambda g, x, y, f, sp, tail: sp.join(p for p in (g, "X" + x, "Y" + y, f) if p) + tail,
    st.sampled_from(["G0", "G1", "G00", "G01", "g1", "G2", "M3", "M5", "G91", "G90", "G20"]),
    _number, _number,
    st.sampled_from(["", "F3000", "f1500.5", "F0", "F-5", "F 600"]),
    st.sampled_from([" ", "", "\t", "  "]),
    st.sampled_from(["", " ; note", ";", " (c)", " ; a*b", " ;("]))


@settings(max_examples=150, deadline=None)
@given(st.lists(_line, min_size=1, max_size=30))
def test_common_lines_read_as_the_general_parser_reads_them(lines):
    # A line number sends every line through the general parser (errors quote it).
    for first in ([], ["G20"], ["G91"], ["F1200"]):
        plain = first + lines
        numbered = [f"N{k} {text}" for k, text in enumerate(plain, 1)]
        for options in (ImportOptions(), ImportOptions(pen_dialect="z"),
                        ImportOptions(pen_dialect="none"), ImportOptions(pen_dialect="laser")):
            ops, errors = _ops_and_errors(plain, options)
            ops_n, errors_n = _ops_and_errors(numbered, options)
            assert ops == ops_n
            assert errors == [{**e, "message": re.sub(r"'N\d+ ", "'", e["message"])}
                              for e in errors_n]


def _chunks_then(error: BaseException):
    """Two chunks of G-code, then `error` (a failing read)."""
    yield "G0 X1 Y1\nM3\n"
    yield "G1 X2 Y2 F600\n"
    raise error


def test_a_failing_read_is_raised_after_the_chunks_before_it():
    # The chunks are read and scanned on a thread of their own (gcode._ahead).
    got = []
    with pytest.raises(OSError, match="disk gone"):
        for op in single_moves(read_ops(_chunks_then(OSError("disk gone")), ImportOptions(),
                                        ErrorLog())):
            got.append(op[:2])
    assert got == [(MOVE, 1), (PEN, 2), (MOVE, 3)]


def test_a_reader_stopped_early_leaves_no_thread_behind():
    def endless():
        while True:
            yield "G1 X1 Y1 F600\nG1 X2 Y2\n"
    ops = read_ops(endless(), ImportOptions(), ErrorLog())
    next(ops)
    ops.close()
    assert not [t for t in threading.enumerate() if t.name == "gcode-scan"]
