"""`make flash BOARD=...` against the boards' real bootloaders.

Debian's arduino-core-avr ships the Uno's optiboot and the Mega's stk500v2
bootloader. plotsim runs the bootloader from reset on an erased flash with
the UART on a pty; the very `make flash` command (avrdude -c arduino for the
Uno, -c wiring for the Mega) programs our HEX through it with the chip's own
SPM instructions and verifies it; the bootloader then starts the application,
which must greet with the GRBL banner and plot a square.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from tests.fixtures.grbl import Grbl
from tests.fixtures.plotsim import FIRMWARE_DIR, PLOTSIM, Plotter, board_firmware

pytestmark = pytest.mark.e2e

BOOTLOADERS = Path("/usr/share/arduino/hardware/arduino/avr/bootloaders")
CASES = {
    "uno-cnc-shield": BOOTLOADERS / "optiboot" / "optiboot_atmega328.hex",
    "mega-ramps14": BOOTLOADERS / "stk500v2" / "stk500boot_v2_mega2560.hex",
}


@pytest.mark.parametrize("board", list(CASES))
def test_make_flash_through_the_real_bootloader(sim_build, tmp_path, board: str) -> None:
    bootloader = CASES[board]
    assert bootloader.exists(), "scripts/setup-system test installs arduino-core-avr"
    board_firmware(board)
    # real time: the bootloader waits about a second for the programmer
    # the command line ends "--bootloader HEX": no ELF, the flash starts erased
    chip = Plotter(PLOTSIM, bootloader, tmp_path / "ee.bin", 1, (0, 0),
                   ["--board", board, "--bootloader"]).start()
    try:
        flash = subprocess.run(
            ["make", "-C", str(FIRMWARE_DIR), "flash", f"BOARD={board}", f"PORT={chip.port}"],
            capture_output=True, text=True, timeout=180)
        assert flash.returncode == 0, flash.stdout + flash.stderr
        assert "bytes of flash verified" in flash.stdout + flash.stderr
        g = Grbl(chip.port)
        try:
            g.reset(30)  # the power-up banner went out while avrdude held the port
            g.ok("$X")
            for line in ("G0 X10 Y10", "M3", "G1 X30 F3000", "G1 Y30", "G1 X10", "G1 Y10", "M5"):
                g.ok(line)
            g.wait_state("Idle", 60)
        finally:
            g.close()
        trace = chip.wait_trace(lambda t: t["pen_lifts"] == 1, timeout=10)
        corners = [(x, y) for x, y, _t in trace["strokes"][0]]
        assert corners == [(10, 10), (30, 10), (30, 30), (10, 30), (10, 10)], json.dumps(corners)
    finally:
        chip.cleanup()
