"""A job's estimate through the real path: a dense drawing uploaded to a real `plotbridge
serve`, imported and estimated for its board (the compact wire lines with N words, our
firmware's line time), then plotted by that server on a virtual plotter in real time;
the job's `estimate_s` against the simulated plot time from the plotter's trace."""

from __future__ import annotations

import math

import pytest

from tests.fixtures.plot_time import estimate_and_plot, idle
from tests.fixtures.server import running_server

pytestmark = pytest.mark.e2e


def spiral(lines: int = 1200, segment: float = 0.5, feed: int = 6000) -> str:
    """A spiral of short segments, drawn in one stroke: every line is a short move, and
    the planner's look-ahead and the lines' pace set the time (~6 s)."""
    out = ["G0 X102 Y100", "M3"]
    t = 0.0
    for _ in range(lines):
        r = 2 + 0.25 * t
        t += segment / r
        r = 2 + 0.25 * t
        out.append(f"G1 X{100 + r * math.cos(t):.3f} Y{100 + r * math.sin(t):.3f} F{feed}")
    return "\n".join([*out, "M5"]) + "\n"


def test_a_dense_drawings_estimate_is_its_simulated_plot_time(plotter_factory, tmp_path):
    # Real time: the server's own streaming is part of the plot, as for a user; the plot
    # time is simulated time, read from the trace, so a slow machine does not stretch it
    # (the planner keeps ~0.15 s of these moves queued ahead of the stream).
    plotter = plotter_factory(speed=1)
    with running_server(tmp_path / "server-data", ["--serial", plotter.port]) as server:
        idle(server)
        drawing = spiral()
        job = server.submit(drawing, start=False)
        predicted, plotted = estimate_and_plot(server, plotter, job["id"])
        trace = plotter.trace()
    print(f"estimate {predicted:.2f} s, simulated plot {plotted:.2f} s")
    end = [float(w[1:]) for w in drawing.splitlines()[-2].split()[1:3]]
    assert len(trace["strokes"]) == 1     # all of it drawn, to its end
    assert trace["strokes"][0][-1][:2] == pytest.approx(end, abs=0.02)
    assert predicted == pytest.approx(plotted, rel=0.03), (predicted, plotted)
