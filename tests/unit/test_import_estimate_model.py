"""The estimate's motion model follows the board's firmware: stock GRBL's (planner depth,
line time) when `$I` names another build than ours, ours when it names ours or nothing;
the planner depth and line numbers the board's `$I` reported, and a library build that
holds that depth."""

from __future__ import annotations

from pathlib import Path

import pytest
from plotbridge.grbl import build_of
from plotbridge.importing import MachineProfile
from plotbridge.jobs.imports import run_import
from plotbridge.motion import library
from plotbridge.motion.timing import GRBL_LINE_S, GRBL_PLANNER_BLOCKS

SETTINGS = {110: 5000.0, 111: 5000.0, 120: 800.0, 121: 800.0, 130: 300.0, 131: 220.0}


@pytest.mark.parametrize("firmware, build", [
    ("1.1h.20190825", "20190825"), ("1.1h.plotbridge", "plotbridge"), ("1.1h", None),
    (None, None), ("1.1f.", None),
])
def test_build_of_the_version(firmware, build):
    assert build_of(firmware) == build


@pytest.mark.parametrize("firmware, stock", [
    ("1.1h.20190825", True), ("1.1f.20170801", True), ("1.1h.plotbridge", False),
    ("1.1h.PlotBridge", False), ("1.1h", False), (None, False),
])
def test_profile_for_the_firmware(firmware, stock):
    p = MachineProfile.for_board(SETTINGS, firmware)
    assert p.max_rate == (5000.0, 5000.0) and p.accel == (800.0, 800.0)   # its settings
    assert (p.planner_blocks == GRBL_PLANNER_BLOCKS and p.plan_block_s == GRBL_LINE_S) is stock


def dense_svg(path: Path) -> Path:
    """Many short collinear segments: the line time decides the plot time."""
    pts = " ".join(f"{10 + i * 0.1:.1f},50" for i in range(600))
    path.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="100mm" '
                    f'viewBox="0 0 200 100"><polyline points="{pts}" fill="none" '
                    'stroke="black"/></svg>')
    return path


def estimate(tmp_path: Path, firmware: str | None, **board) -> float:
    src = dense_svg(tmp_path / "d.svg")
    out = run_import("file", str(src), "d.svg", str(tmp_path / f"out-{firmware}-{len(board)}"),
                     {"optimize": False, "feed": 6000.0},
                     {"settings": SETTINGS, "firmware": firmware, **board})
    assert out[0] == "ok", out
    return out[1]["estimate_s"]


def test_the_stock_grbl_estimate_is_longer_for_short_lines(tmp_path):
    ours = estimate(tmp_path, "1.1h.plotbridge")
    assert estimate(tmp_path, None) == ours
    stock = estimate(tmp_path, "1.1h.20190825")
    assert stock > ours * 1.1


@pytest.mark.parametrize("profile, depth, build", [
    (None, 0, "uno-cnc-shield"), ("uno-cnc-shield", 33, "uno-cnc-shield"),
    ("mega-l298n", 0, "mega-l298n"), ("uno-uln2003", 0, "uno-uln2003"),
    # a Mega reporting 63 blocks behind a server left at the default profile
    ("uno-cnc-shield", 63, "mega-ramps14"), (None, 15, "uno-cnc-shield"),
])
def test_the_library_build_holds_the_boards_planner(profile, depth, build):
    assert library.build_holding(profile, depth) == build


def test_what_the_board_said_of_itself_sets_the_model():
    ours = MachineProfile.for_board(SETTINGS, "1.1h.plotbridge", "mega-l298n", 63, False)
    assert (ours.build, ours.planner_blocks, ours.line_numbers) == ("mega-l298n", 63, False)
    unread = MachineProfile.for_board(SETTINGS, None, "mega-l298n")
    assert (unread.planner_blocks, unread.line_numbers) == (0, True)   # the build's depth
    stock = MachineProfile.for_board(SETTINGS, "1.1h.20190825", None, 15, False)
    assert (stock.planner_blocks, stock.plan_block_s, stock.line_numbers) == (
        15, GRBL_LINE_S, False)


def test_a_deeper_planner_plots_short_lines_faster_at_low_acceleration(tmp_path, monkeypatch):
    # 0.1 mm segments at 100 mm/s^2: the look-ahead's length caps the speed
    monkeypatch.setitem(SETTINGS, 120, 100.0)
    monkeypatch.setitem(SETTINGS, 121, 100.0)
    uno = estimate(tmp_path, "1.1h.plotbridge", profile=None, planner_blocks=33)
    mega = estimate(tmp_path, "1.1h.plotbridge", profile=None, planner_blocks=63)
    assert mega < uno * 0.9, (mega, uno)
