"""GRBL 1.1 protocol parsing and buffer accounting (plotbridge.grbl)."""

import pytest
from hypothesis import given
from hypothesis import strategies as st
from plotbridge.grbl import (
    RX_BUFFER_SIZE,
    CharCounter,
    LineSplitter,
    alarm_message,
    buffers_from_feedback,
    classify,
    cost,
    error_message,
    line_problem,
    option_letters,
    parse_status,
    version_from_feedback,
)


def test_status_full_report():
    s = parse_status("<Run|MPos:12.000,3.500,0.000|Bf:15,128|FS:3000,0|Pn:XY|A:S>")
    assert s is not None
    assert s.state == "Run" and s.sub_state is None
    assert s.mpos == (12.0, 3.5, 0.0)
    assert (s.planner_free, s.rx_free) == (15, 128)
    assert (s.feed, s.speed) == (3000.0, 0.0)
    assert s.pins == "XY" and s.accessories == "S"


def test_status_substate_wpos_wco_line_overrides():
    s = parse_status("<Hold:0|WPos:-1.5,2.25,0.000|WCO:10,0,0|F:500|Ln:42|Ov:100,50,120>")
    assert s is not None
    assert s.state == "Hold" and s.sub_state == 0
    assert s.wpos == (-1.5, 2.25, 0.0) and s.wco == (10.0, 0.0, 0.0) and s.mpos is None
    assert s.feed == 500.0 and s.line == 42 and s.overrides == (100, 50, 120)


@pytest.mark.parametrize("line", [
    "<Idle|MPos:1,2,3",            # unterminated
    "<Bogus|MPos:1,2,3>",          # unknown state
    "<Idle|MPos:1,x,3>",           # bad number
    "<Idle|Bf:15>",                # Bf needs two values
    "<Idle|MPos>",                 # field without value
    "<Idle,MPos:1,2,3>",           # GRBL 0.9 syntax
    "<Alarm:x>",                   # non-numeric sub-state
    "ok",
])
def test_status_rejects_malformed(line):
    assert parse_status(line) is None


def test_status_ignores_unknown_fields():
    s = parse_status("<Idle|MPos:0,0,0|Zz:1,2>")
    assert s is not None and s.mpos == (0.0, 0.0, 0.0)


@pytest.mark.parametrize(("line", "kind", "payload"), [
    ("ok", "ok", None),
    ("error:20", "error", 20),
    ("error:", "error", None),
    ("ALARM:3", "alarm", 3),
    ("[MSG:'$H'|'$X' to unlock]", "msg", "'$H'|'$X' to unlock"),
    ("[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]", "feedback",
     "GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0"),
    ("Grbl 1.1h ['$' for help]", "banner", "1.1h"),
    ("$110=6000.000", "setting", (110, 6000.0)),
    ("$5=0", "setting", (5, 0.0)),
    ("$N0=G21", "other", "$N0=G21"),
    ("hello", "other", "hello"),
    ("<Idle|MPos:1,x>", "other", "<Idle|MPos:1,x>"),
])
def test_classify(line, kind, payload):
    assert classify(line) == (kind, payload)


def test_classify_status_payload():
    kind, payload = classify("<Idle|MPos:0,0,0>")
    assert kind == "status" and payload.state == "Idle"


def test_messages_and_version():
    assert "feed rate" in error_message(22)
    assert "unknown error 99" == error_message(99)
    assert "limit" in alarm_message(1)
    assert "emergency" in alarm_message(10)
    assert version_from_feedback("VER:1.1h.20190825:") == "1.1h.20190825"
    assert version_from_feedback("OPT:V,15,128") is None
    assert buffers_from_feedback("OPT:V,15,128") == (15, 128)
    assert buffers_from_feedback("OPT:,17,64") == (17, 64)
    assert buffers_from_feedback("OPT:V") is None
    assert buffers_from_feedback("VER:1.1h:") is None


def test_option_letters_say_whether_the_board_numbers_lines():
    assert option_letters("OPT:VN,15,128") == "VN"
    assert option_letters("OPT:N,63,128") == "N"
    assert option_letters("OPT:#I,33,128") == "#I"
    assert option_letters("OPT:,63,128") == ""
    assert option_letters("VER:1.1h:") is None


def test_line_problem():
    assert line_problem("G1 X10 Y10 F3000") is None
    assert "cannot be sent" in line_problem("G1 X1 ?")
    assert "cannot be sent" in line_problem("G1 X1\x18")
    assert "cannot be sent" in line_problem("G1 X1 é")
    assert line_problem("G1" + " " * 125) is None          # 127 + newline = 128
    assert "at most 127" in line_problem("G1" + " " * 126)


def test_counter_accounting_and_order():
    c = CharCounter()
    c.push(cost("G1 X1"), "a")
    c.push(cost("G1 X22"), "b")
    assert c.outstanding == 6 + 7 and len(c) == 2
    assert c.peek() == "a"
    assert c.ack() == "a" and c.outstanding == 7
    assert c.ack() == "b" and c.outstanding == 0
    with pytest.raises(LookupError):
        c.ack()


def test_counter_never_over_capacity():
    c = CharCounter()
    c.push(100)
    assert not c.fits(29) and c.fits(28)
    with pytest.raises(OverflowError):
        c.push(29)
    c.push(28)
    assert c.free == 0
    assert c.clear() == [None, None] and c.outstanding == 0


@given(st.lists(st.integers(min_value=1, max_value=RX_BUFFER_SIZE), max_size=200))
def test_counter_property(sizes):
    c = CharCounter()
    acked = 0
    for i, size in enumerate(sizes):
        while not c.fits(size):
            assert c.ack() == acked
            acked += 1
        c.push(size, i)
        assert c.outstanding <= RX_BUFFER_SIZE


def test_splitter_lines_across_chunks():
    sp = LineSplitter()
    assert sp.feed(b"o") == ([], [])
    assert sp.feed(b"k\r\nerr") == (["ok"], [])
    assert sp.feed(b"or:2\r\n<Idle>\n") == (["error:2", "<Idle>"], [])


def test_splitter_drops_garbage_keeps_text():
    sp = LineSplitter()
    lines, problems = sp.feed(b"\xff\xfe\x00ok\r\n\x00\x00\n\xc3\xa9\n")
    assert lines == ["ok"]
    assert len(problems) == 3


def test_splitter_overlong_line_dropped_until_newline():
    sp = LineSplitter(max_bytes=16)
    lines, problems = sp.feed(b"x" * 10)
    assert lines == []
    lines, problems = sp.feed(b"y" * 10 + b"z" * 50)
    assert lines == [] and len(problems) == 1
    lines, problems = sp.feed(b"still the same line\nok\n")
    assert lines == ["ok"] and problems == []


@given(st.binary(max_size=600))
def test_splitter_never_raises(data):
    sp = LineSplitter()
    lines, _ = sp.feed(data)
    for line in lines:
        assert line.isascii() and "\n" not in line


def test_settings_metadata_covers_the_firmware_table():
    import re
    from pathlib import Path

    from plotbridge.settings_meta import SETTINGS

    doc = (Path(__file__).resolve().parents[2] / "docs" / "INTERNALS.md").read_text()
    section = doc.split("## Firmware settings", 1)[1].split("\n## ", 1)[0]
    numbers = {int(n) for row in re.findall(r"^\| ([\d, ]+) \|", section, re.M)
               for n in row.split(",")}
    assert len(numbers) > 25
    assert numbers <= set(SETTINGS), sorted(numbers - set(SETTINGS))
    assert all(info.name and info.description for info in SETTINGS.values())
