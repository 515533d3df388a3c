"""G-code from the tools people plot with, each fixture written in that tool's style:
pen-down length and bounds within 1%, layers at pauses and tool changes, and what was
dropped reported as warnings."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from plotbridge.importing import ImportFailed
from plotbridge.importing.gcode import sniff_dialect

from tests.fixtures.imports import program_lines, run_import

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "gcode"

CASES = {
    # name: (pen-down mm, bounds, layer count, words that must appear in the warnings)
    "vpype_gwrite": (100.0, (10, 10, 40, 30), 1, ("feed",)),
    # the registration dot (a pen-down with no move) is not drawn nor in the bounds;
    # M01's pause before anything is drawn names the one layer
    "unicorn_m300": (70.0, (10, 10, 50, 40), 1, ("M18", "M17", "pen-down with no move")),
    "makelangelo": (60.0, (10, 10, 60, 30), 2, ()),
    "fusion360": (100.0, (10, 10, 40, 30), 1, ()),
    "inkscape_laser": (50.0 + math.hypot(10, 20), (10, 10, 60, 30), 1, ()),
    "svg2gcode_nopen": (40.0, (10, 10, 50, 40), 1, ()),
    "grbl_console": (20.0, (10, 10, 20, 20), 1, ("$H", "$X", "?", "M17", "M84")),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_dialect_fixture(tmp_path, name):
    length, bounds, layers, warned = CASES[name]
    text = (FIXTURES / f"{name}.gcode").read_text()
    r = run_import(tmp_path, text, f"{name}.gcode")
    assert r.stats["pen_down_mm"] == pytest.approx(length, rel=0.01)
    got = (r.bounds["min_x"], r.bounds["min_y"], r.bounds["max_x"], r.bounds["max_y"])
    assert got == pytest.approx(bounds, rel=0.01, abs=0.01)
    assert len(r.layers) == layers
    messages = " ".join(w["message"] for w in r.warnings)
    for word in warned:
        assert word in messages


def test_makelangelo_layers_pause_between_pens(tmp_path):
    r = run_import(tmp_path, (FIXTURES / "makelangelo.gcode").read_text(), "m.gcode")
    lines = program_lines(r)
    first, second = r.layers
    assert first["name"] == "Ready black and click"
    assert second["name"] == "Ready red and click"
    assert first["pen_down_mm"] == pytest.approx(40) and second["pen_down_mm"] == pytest.approx(20)
    # the pen-change pause: M0 on the line before the second layer's first line, after
    # the first layer's last M5 (travel may come between) and before the next M3
    pause = second["first_line"] - 1
    assert lines[pause - 1] == "M0" and lines.count("M0") == 1
    assert first["last_line"] == pause - 1
    before = [ln for ln in lines[:pause - 1] if ln.startswith("M")]
    after = [ln for ln in lines[pause:] if ln.startswith("M")]
    assert before[-1] == "M5" and after[0] == "M3"
    assert second["estimate_s"] > 0 and first["estimate_s"] > 0


def test_laser_travel_is_not_drawn_unless_dialect_says_m3(tmp_path):
    text = (FIXTURES / "inkscape_laser.gcode").read_text()
    laser = run_import(tmp_path, text, "l.gcode")
    m3 = run_import(tmp_path, text, "l.gcode", pen_dialect="m3")
    assert m3.stats["pen_down_mm"] > laser.stats["pen_down_mm"] + 30   # G0 drawn as lines


def test_g92_offsets_moves(tmp_path):
    r = run_import(tmp_path, "G0 X10 Y10\nG92 X0 Y0\nM3\nG1 X5 Y0 F1000\nM5\n", "o.gcode")
    assert (r.bounds["min_x"], r.bounds["max_x"]) == (10.0, 15.0)


def test_g28_with_intermediate_point_and_g30_stored_position(tmp_path):
    text = ("G0 X20 Y20\nG30.1\nG0 X5 Y5\nM3\nG1 X10 Y5 F1000\nG28 X30 Y30\n"
            "G30\nM3\nG1 X25 Y20 F1000\nM5\n")
    lines = program_lines(run_import(tmp_path, text, "h.gcode"))
    i = lines.index("G0 X30.000 Y30.000")
    assert lines[i - 1] == "M5" and lines[i + 1] == "G0 X0.000 Y0.000"
    assert lines[i + 2] == "G0 X20.000 Y20.000"


def test_trailing_travel_home_outside_the_area_is_clamped_with_a_warning(tmp_path):
    r = run_import(tmp_path, "G0 X10 Y10\nM3\nG1 X20 Y10 F1000\nM5\nG0 X-5 Y-5\n", "t.gcode")
    assert any("clamped" in w["message"] for w in r.warnings)
    assert program_lines(r)[-2] == "G0 X0.000 Y0.000"


def test_travel_outside_the_area_before_a_stroke_is_refused(tmp_path):
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, "G0 X-5 Y-5\nM3\nG1 X20 Y10 F1000\nM5\n", "t.gcode")
    assert e.value.errors[0]["line"] == 1


def test_comments_of_any_length_but_not_commands(tmp_path):
    comment = "(" + "x" * 2000 + ")"
    r = run_import(tmp_path, f"{comment}\nG0 X1 Y1 {comment}\nM3\nG1 X5 F100\nM5\n", "c.gcode")
    assert r.stats["pen_down_mm"] == pytest.approx(4)
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, "G1 X1 " + "Y1 " * 200 + "F100\n", "c.gcode")
    assert "longer than" in e.value.errors[0]["message"]


@pytest.mark.parametrize("line", ["G81 X1 Y1 Z-1 R1", "M98 P1000", "#1=5"])
def test_refused_where_a_file_really_cannot_plot(tmp_path, line):
    with pytest.raises(ImportFailed) as e:
        run_import(tmp_path, f"G0 X1 Y1\n{line}\nM3\nG1 X5 F100\n", "r.gcode")
    assert e.value.errors[0]["line"] == 2


def test_m280_threshold_and_explicit_dialect(tmp_path):
    text = "M280 P0 S90\nG0 X10 Y10\nM280 P0 S30\nG1 X20 Y10 F1000\nM280 P0 S90\n"
    assert run_import(tmp_path, text, "s.gcode").stats["pen_down_mm"] == pytest.approx(10)
    r = run_import(tmp_path, text, "s.gcode", pen_dialect="none")
    assert r.stats["pen_down_mm"] == pytest.approx(10)     # G1 draws, G0 travels


@pytest.mark.parametrize(("head", "dialect"), [
    ("G0 X1\nm300 s30\n", "m300"), ("G0 X1\nM 300 S30\n", "m300"), ("m\t280 P0 S90\n", "m280"),
    ("G1 X300 F3000\nM3\n", "m3"), ("M3000\nM2800\nG0 X1\n", "none"), ("(M300)\nG0 X1\n", "none"),
])
def test_servo_words_are_sniffed_in_either_case(head, dialect):
    assert sniff_dialect(head) == dialect


# ---- issue 32: dwell units, pen-downs placed with the drawing, dots ----------------

@pytest.mark.parametrize(("head", "dwell", "seconds"), [
    ("M300 S50\n", "G4 P150 (wait 150ms)", "0.150"),          # Unicorn: milliseconds
    ("M280 P0 S90 T250\n", "G4 P250", "0.250"),              # Makelangelo (Marlin): ms
    ("M280 P0 S90 T250\n", "G4 S2", "2.000"),                # Marlin's S: seconds
    ("M5\n", "G4 P1.5", "1.500"),                            # GRBL: seconds
])
def test_dwells_are_written_in_grbl_seconds_per_dialect(tmp_path, head, dwell, seconds):
    down = {"M300 S50\n": "M300 S30", "M280 P0 S90 T250\n": "M280 P0 S20"}.get(head, "M3")
    up = {"M300 S50\n": "M300 S50", "M280 P0 S90 T250\n": "M280 P0 S90"}.get(head, "M5")
    r = run_import(tmp_path, f"G21\nG90\n{head}G0 X10 Y10\n{down}\n{dwell}\nG1 X20 Y10 F600\n"
                   f"{up}\n")
    assert f"G4 P{seconds}" in program_lines(r)
    assert r.estimate_s < 5 + float(seconds)


def test_the_unicorn_file_is_estimated_with_its_dwells_in_milliseconds(tmp_path):
    r = run_import(tmp_path, (FIXTURES / "unicorn_m300.gcode").read_text(), "u.gcode")
    dwells = [float(ln[4:]) for ln in program_lines(r) if ln.startswith("G4")]
    assert dwells and all(d == pytest.approx(0.15) for d in dwells)
    assert r.estimate_s < 10


VPYPE_PLACED = """G21
G90
M3
G0 X0 Y0
M5
G0 X10 Y10
M3
G1 X50 Y10 F3000
G1 X50 Y40
M5
"""


def test_a_pen_down_with_no_move_is_neither_drawn_nor_in_the_bounds(tmp_path):
    r = run_import(tmp_path, VPYPE_PLACED, "v.gcode", paper="A5", fit=True, margin=10)
    lines = program_lines(r)
    first_down = lines.index("M3")
    assert lines[first_down - 1].startswith("G0 ") and lines.count("M3") == 1
    # fitted from the stroke's own bounds (40 x 30 mm) into A5's 128 x 190 mm
    w = r.bounds["max_x"] - r.bounds["min_x"]
    assert w == pytest.approx(128, abs=0.01)
    assert r.stats["pen_down_mm"] == pytest.approx(128 / 40 * 70, rel=1e-3)
    assert any("pen-down with no move" in w["message"] for w in r.warnings)


def test_a_first_stroke_from_the_origin_goes_down_where_placement_puts_it(tmp_path):
    r = run_import(tmp_path, "G21\nG90\nM3\nG1 X20 Y0 F600\nG1 X20 Y10\nM5\n", "o.gcode",
                   dx=30, dy=40)
    lines = program_lines(r)
    k = lines.index("M3")
    assert lines[k - 1] == "G0 X30.000 Y40.000"
    assert r.stats["pen_down_mm"] == pytest.approx(30)
    assert (r.bounds["min_x"], r.bounds["min_y"]) == (30, 40)


def test_dots_in_a_file_of_common_lines_are_dropped_and_counted(tmp_path):
    strokes = "".join(f"G0 X{5 + k} Y5\nM3\nM5\nG0 X{5 + k} Y20\nM3\nG1 X{6 + k} Y30 F900\nM5\n"
                      for k in range(50))
    r = run_import(tmp_path, "G21\nG90\n" + strokes, "d.gcode")
    assert program_lines(r).count("M3") == 50
    assert r.bounds["min_y"] == 20
    (dots,) = [w for w in r.warnings if "pen-down with no move" in w["message"]]
    assert dots["count"] == 50 and dots["line"] == 4


def test_the_laser_sniff_and_comment_stripping_are_linear(tmp_path):
    import time
    for head in ("M3\n" * 300_000, "(" * 1_000_000, "G1 X1 (" * 150_000, "M3 " * 300_000):
        start = time.process_time()
        sniff_dialect(head)
        assert time.process_time() - start < 1.0, head[:20]


def test_travel_outside_the_area_that_comes_back_before_a_stroke_is_clamped(tmp_path):
    r = run_import(tmp_path, "G0 X-5 Y-5\nG0 X10 Y10\nM3\nG1 X20 Y10 F1000\nM5\n", "t.gcode")
    assert any("clamped" in w["message"] and w["line"] == 1 for w in r.warnings)
    assert r.stats["pen_down_mm"] == pytest.approx(10)
