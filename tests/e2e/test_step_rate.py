"""The step interrupt at its rated speed: a two-axis move at 50 kHz per axis
through the real firmware in the virtual plotter, checked on the pins that
plotsim decodes (pulse widths, direction setup, rate, exact steps, time)."""

from __future__ import annotations

import math

import pytest

from tests.fixtures.grbl import Grbl, clean, mpos

pytestmark = pytest.mark.e2e

STEPS_PER_MM = 80
RATE_HZ = 50_000
ACCEL = 8000  # mm/s^2


def test_two_axes_at_50_khz_without_late_steps_or_short_pulses(plotter_factory) -> None:
    per_axis = RATE_HZ / STEPS_PER_MM  # mm/s
    # the overspeed check allows the jitter of an edge (a few us) but not a faster rate
    plotter = plotter_factory(args=["--max-step-rate", str(int(RATE_HZ * 1.6))])
    g = Grbl(plotter.port)
    try:
        g.reset()
        feed = per_axis * 60 * math.sqrt(2)
        for line in ["$X", f"$110={per_axis * 60:.0f}", f"$111={per_axis * 60:.0f}",
                     f"$120={ACCEL}", f"$121={ACCEL}", "G0 X5 Y5", "M3"]:
            g.ok(line)
        # both moves in the receive buffer at once, so the corner's time on the
        # simulated clock is where the fast move starts (no wait for the host)
        g.ser.write(f"G1 X5 Y6 F600\nG1 X205 Y206 F{feed:.0f}\n".encode())
        g.wait_for(r"^ok$")
        g.wait_for(r"^ok$")
        g.wait_state("Idle")
        trace = plotter.trace()
        clean(trace)  # no short pulse, no direction change too close to an edge
        (stroke,) = trace["strokes"]
        assert [(round(x, 3), round(y, 3)) for x, y, _ in stroke] == [(5, 5), (5, 6), (205, 206)]
        assert trace["steps"] == {"x": 205 * STEPS_PER_MM, "y": 206 * STEPS_PER_MM}
        assert mpos(g.status()) == (205.0, 206.0)
        assert trace["min_pulse_us"] >= 4.0  # $0 default
        # the cruise really runs at the rated step rate on both axes ...
        assert trace["max_step_rate"]["x"] >= RATE_HZ * 0.99
        assert trace["max_step_rate"]["y"] >= RATE_HZ * 0.99
        # ... and no step comes late: the move takes the planned time (from
        # the corner's few mm/s: a trapezoid, cruise time plus one ramp)
        took = stroke[2][2] - stroke[1][2]
        v = per_axis * math.sqrt(2)  # along the diagonal, as is the acceleration
        planned = 200 * math.sqrt(2) / v + v / (ACCEL * math.sqrt(2))
        assert planned * 0.99 <= took <= planned * 1.01, (took, planned)
        g.ok("M5")
    finally:
        g.close()
