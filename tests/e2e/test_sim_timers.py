"""plotsim makes simavr's timers behave as the ATmega328P's (DESIGN.md,
"simavr 1.6: facts that bite"), and the pulse widths in the trace show it.

The timers test firmware (firmware/sim/testfw/timers.c) makes one X step
pulse per command, ended by a Timer1 interrupt; plain simavr 1.6 gives
4100 us, no interrupt at all, and 4100 us for these three.
"""

from __future__ import annotations

import pytest
import serial

from tests.fixtures.plotsim import Plotter, PlotterFactory, SimBuild

pytestmark = pytest.mark.e2e


@pytest.fixture
def timers(plotter_factory: PlotterFactory, sim_build: SimBuild) -> Plotter:
    return plotter_factory(firmware=sim_build.timers)


def pulse_after(plotter: Plotter, port: serial.Serial, command: bytes) -> float:
    plotter.clear()
    port.write(command)
    assert port.readline() == command + b"\n", "the timer interrupt never came"
    return plotter.trace()["min_pulse_us"]


@pytest.mark.parametrize(
    ("command", "low", "high"),
    [
        (b"T", 50, 60),  # TCNT1 preset to 65536-800 while stopped: 800 cycles
        (b"C", 0.5, 10),  # CTC with OCR1A = 0 matches at once
        (b"M", 0.5, 10),  # overflow flag already set when TOIE1 is enabled
    ],
)
def test_timer_behaves_as_the_chip(
    timers: Plotter, command: bytes, low: float, high: float
) -> None:
    with serial.Serial(timers.port, 115200, timeout=5) as port:
        assert low < pulse_after(timers, port, command) < high
