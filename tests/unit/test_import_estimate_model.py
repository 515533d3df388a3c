"""The estimate's motion model follows the board's firmware: stock GRBL's (planner depth,
line time) when `$I` names another build than ours, ours when it names ours or nothing."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest
from plotbridge.grbl import build_of
from plotbridge.importing import MachineProfile
from plotbridge.jobs.imports import Importer, run_import
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


def estimate(tmp_path: Path, firmware: str | None) -> float:
    src = dense_svg(tmp_path / "d.svg")
    out = run_import("file", str(src), "d.svg", str(tmp_path / f"out-{firmware}"),
                     {"optimize": False, "feed": 6000.0}, SETTINGS, firmware)
    assert out[0] == "ok", out
    return out[1]["estimate_s"]


def test_the_stock_grbl_estimate_is_longer_for_short_lines(tmp_path):
    ours = estimate(tmp_path, "1.1h.plotbridge")
    assert estimate(tmp_path, None) == ours
    stock = estimate(tmp_path, "1.1h.20190825")
    assert stock > ours * 1.1


def test_the_importer_hands_the_boards_firmware_to_the_worker(tmp_path, monkeypatch):
    seen = []
    importer = Importer(tmp_path / "jobs", settings=lambda: SETTINGS,
                        firmware=lambda: "1.1h.20190825")

    async def inline(function, *args, size=0):
        seen.append(args[-1])
        return function(*args)

    monkeypatch.setattr(importer.workers, "call", inline)
    try:
        (tmp_path / "jobs").mkdir()
        src = dense_svg(tmp_path / "upload.svg")
        _, _, result = asyncio.run(importer.create("file", src, "d.svg",
                                                          {"optimize": False, "feed": 6000.0}))
    finally:
        importer.close()
    assert seen == ["1.1h.20190825"]
    assert result.estimate_s == pytest.approx(estimate(tmp_path, "1.1h.20190825"), abs=0.1)
