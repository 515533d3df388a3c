"""The compact wire format: shorter lines, the same motor steps."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st
from plotbridge.program.wire import Compactor, compact, number, numbered, on_step, step_of

SPM = (80.0, 80.0)


def wire(lines, spm=SPM):
    return [t for _, t in compact(enumerate(lines, 1), spm)]


def test_numbers_drop_trailing_and_leading_zeros():
    assert number(0.5) == ".5"
    assert number(-0.5) == "-.5"
    assert number(12.0) == "12"
    assert number(-0.0) == "0"
    assert number(120.25) == "120.25"


def test_a_typical_short_segment_is_12_to_14_bytes():
    out = wire(["G1 X12.345 Y67.890 F3000", "G1 X12.845 Y67.390 F3000",
                "G1 X13.345 Y67.113 F3000"])
    assert out[0] == "G1X12.35Y67.89F3000"
    assert out[1:] == ["X12.85Y67.39", "X13.35Y67.11"]
    assert all(12 <= len(t) + 1 <= 14 for t in out[1:])


def test_modal_words_are_dropped_only_when_repeated():
    out = wire(["G0 X1.000 Y1.000", "M3", "G1 X2.000 Y1.000 F1500", "G1 X3.000 Y1.000 F2000",
                "M5", "G0 X4.000 Y4.000", "G0 X5.000 Y4.000", "G4 P0.500",
                "G1 X6.000 Y4.000 F2000"])
    assert out == ["G0X1Y1", "M3", "G1X2Y1F1500", "X3Y1F2000", "M5", "G0X4Y4", "X5Y4",
                   "G4P0.500", "G1X6Y4F2000"]   # after G4 nothing is assumed


def test_arc_centres_stay_where_they_were():
    c = Compactor(SPM)
    c.line("G1 X20.013 Y10.000 F3000")   # sent as X20.01: same step
    out = c.line("G2 X30.000 Y20.000 I10.000 J0.000 F3000")
    assert out == "G2X30Y20I10.003J0"


def parse(lines):
    """Positions of a wire or readable program, as a GRBL parser sees them."""
    x = y = 0.0
    out = []
    for text in lines:
        i = 0
        words = {}
        while i < len(text):
            j = i + 1
            while j < len(text) and (text[j].isdigit() or text[j] in ".-"):
                j += 1
            words[text[i]] = float(text[i + 1:j])
            i = j
        x, y = words.get("X", x), words.get("Y", y)
        out.append((x, y))
    return out


coordinate = st.floats(min_value=-500, max_value=500).map(lambda v: round(v, 3))


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["G0", "G1"]), coordinate, coordinate,
                          st.sampled_from([1000, 1500, 3000])), min_size=1, max_size=30),
       st.sampled_from([(80.0, 80.0), (100.0, 40.0), (6.25, 5.0), (400.0, 400.0)]))
def test_compaction_never_changes_a_step(moves, spm):
    readable = [f"{g} X{x:.3f} Y{y:.3f}" + (f" F{f}" if g == "G1" else "")
                for g, x, y, f in moves]
    compacted = wire(readable, spm)
    assert all(" " not in t for t in compacted)
    assert sum(map(len, compacted)) <= sum(map(len, readable))
    for (xa, ya), (xb, yb) in zip(parse(t.replace(" ", "") for t in readable),
                                  parse(compacted), strict=True):
        assert step_of(xa, spm[0]) == step_of(xb, spm[0])
        assert step_of(ya, spm[1]) == step_of(yb, spm[1])


@given(coordinate)
def test_on_step_is_never_longer(v):
    assert len(on_step(v, 80.0)) <= len(f"{v:.3f}")


def test_numbered_lines_carry_their_program_line_as_an_n_word():
    assert numbered(12, "X5Y7") == "N12X5Y7"
    assert numbered(10_000_000, "G0X1") == "N10000000G0X1"
    # a preamble line (0), a number GRBL refuses (error:27), a $ command, nothing: as is
    assert numbered(0, "G0X1") == "G0X1"
    assert numbered(10_000_001, "G0X1") == "G0X1"
    assert numbered(3, "$H") == "$H"
    assert numbered(3, "") == ""
