"""One motion model: the estimate (the firmware's planner, arc and segment code built
for the host, plus the host-side timing) against the real firmware in the virtual
plotter, fed what the server sends (compact wire lines with N words); and the compact
wire format against the readable program on the same board."""

from __future__ import annotations

import math
import subprocess

import pytest
from plotbridge.importing import MachineProfile
from plotbridge.motion.estimate import Estimator
from plotbridge.program.wire import compact, numbered

from tests.fixtures.grbl_sender import Board
from tests.fixtures.plotsim import FIRMWARE_ELF

pytestmark = pytest.mark.e2e

PROFILE = MachineProfile()
SIM_SPEED = 1  # real time: the sender's latency on a loaded machine (before the first line,
#   or a stall that lets the planner run dry) becomes as little simulated time as a paced
#   simulator allows; at 2x a loaded machine pushed the plot 1-4 % past the estimate


def program(body: list[str]) -> list[str]:
    return ["G21", "G90", "M5", *body, "M5"]


def short_segments() -> list[str]:
    pts = [(100 + 10 * math.cos(k / 20), 100 + 10 * math.sin(k / 20)) for k in range(250)]
    return program([f"G0 X{pts[0][0]:.3f} Y{pts[0][1]:.3f}", "M3",
                    *(f"G1 X{x:.3f} Y{y:.3f} F3000" for x, y in pts[1:])])


PROGRAMS = {
    "short segments": short_segments(),
    "long lines": program(["G0 X20.000 Y20.000", "M3", "G1 X200.000 Y20.000 F6000",
                           "G1 X200.000 Y150.000 F6000", "G1 X20.000 Y20.000 F6000"]),
    "sharp corners": program(["G0 X20.000 Y20.000", "M3",
                              *(f"G1 X{20 + 3 * k}.000 Y{40 if k % 2 else 20}.000 F5000"
                                for k in range(1, 30))]),
    "arcs": program(["G0 X110.000 Y100.000", "M3",
                     "G3 X90.000 Y100.000 I-10.000 J0.000 F4000",
                     "G2 X70.000 Y100.000 I-10.000 J0.000 F4000",
                     "G3 X110.000 Y100.000 I20.000 J0.000 F2500"]),
    "pen lifts and feeds": program([
        line for k in range(6) for line in (
            f"G0 X{30 + 20 * k}.000 Y30.000", "M3",
            f"G1 X{40 + 20 * k}.000 Y60.000 F{1000 + 800 * k}",
            f"G1 X{30 + 20 * k}.000 Y60.000 F{4000 - 500 * k}", "M5")]),
}


def received(lines: list[str], profile: MachineProfile = PROFILE) -> Estimator:
    """An estimator fed these program lines (the normalized dialect)."""
    e = Estimator(profile)
    down = False
    for n, text in enumerate(lines, 1):
        e.receive(text)
        words = {w[0]: float(w[1:]) for w in text.split()[1:]}
        head = text.split()[0]
        if head in ("G0", "G1"):
            e.move(n, words["X"], words["Y"], words["F"] if head == "G1" else None)
        elif head in ("G2", "G3"):
            e.arc(n, words["X"], words["Y"], words["I"], words["J"], words["F"], head == "G2")
        elif head in ("M3", "M5"):
            e.stop(n, profile.pen_settle_s if (head == "M3") != down else 0.0)
            down = head == "M3"
    return e


def estimate(lines: list[str]) -> float:
    e = received(lines)
    e.flush()
    return e.time


def plot(plotter_factory, lines: list[str], speed: float = SIM_SPEED) -> tuple[dict, float]:
    plotter = plotter_factory(speed=speed)
    board = Board(plotter.port)
    board.command("$X")
    t0 = plotter.trace()["sim_time"]
    board.stream(lines, timeout=300)
    board.wait_idle(timeout=300)
    board.close()
    trace = plotter.trace()
    plotter.stop()
    return trace, t0


def sent(lines: list[str], profile: MachineProfile = PROFILE) -> list[str]:
    """The lines as the server sends them to our firmware (the estimate's bytes)."""
    assert profile.line_numbers
    return [numbered(n, t) for n, t in compact(enumerate(lines, 1), profile.steps_per_mm)]


@pytest.mark.parametrize("name", list(PROGRAMS))
def test_estimate_equals_the_simulated_plot_time(plotter_factory, name):
    lines = PROGRAMS[name]
    trace, t0 = plot(plotter_factory, sent(lines))
    # the program ends with its last stroke and M5: motion ends at the last vertex,
    # and the estimate adds the final pen settle
    measured = trace["strokes"][-1][-1][2] - t0
    predicted = estimate(lines) - PROFILE.pen_settle_s
    print(f"{name}: predicted {predicted:.3f} s, simulated {measured:.3f} s")
    assert predicted == pytest.approx(measured, rel=0.01), (name, predicted, measured)


@pytest.mark.parametrize("name", ["short segments", "arcs", "pen lifts and feeds"])
def test_compact_stream_draws_the_same_steps(plotter_factory, name):
    lines = PROGRAMS[name]
    wire = [text for _, text in compact(enumerate(lines, 1), PROFILE.steps_per_mm)]
    assert sum(map(len, wire)) < 0.75 * sum(map(len, lines))
    readable, _ = plot(plotter_factory, lines, speed=0)
    compacted, _ = plot(plotter_factory, wire, speed=0)
    assert compacted["steps"] == readable["steps"]
    assert compacted["pulses"] == readable["pulses"]
    assert len(compacted["strokes"]) == len(readable["strokes"])
    for a, b in zip(compacted["strokes"], readable["strokes"], strict=True):
        assert [p[:2] for p in a] == [p[:2] for p in b]


# Block speeds: a slow lead-in move keeps the board busy while a window of lines (no
# more than the planner holds) is planned behind it; then the board's planner ring is
# read from simulated RAM (located by the ELF's symbol table) and compared byte for byte
# with the host library's after the same lines. The lead-in's own progress only moves
# the executing block's exit limit, which the slow lead-in never lets bind.
LEAD_IN = "G1 X200.000 Y0.000 F30"
WINDOWS = {
    "short segments": [f"G1 X{200 + 0.4 * k:.3f} Y{0.3 * k * k / 10:.3f} F3000"
                       for k in range(1, 13)],
    "long lines and sharp corners": ["G1 X250.000 Y0.000 F6000", "G1 X250.000 Y100.000 F6000",
                                     "G1 X200.000 Y2.000 F4000", "G1 X260.000 Y3.000 F4000",
                                     "G0 X210.000 Y150.000", "G1 X210.000 Y10.000 F900"],
    "arcs": ["G1 X201.000 Y0.000 F3000", "G3 X202.237 Y0.155 I0.000 J5.000 F3000",
             "G2 X202.829 Y0.245 I0.742 J-2.907 F2000"],
    "feeds changing": [f"G1 X{200 + 2 * k:.3f} Y{k % 3:.3f} F{600 + 700 * k}"
                       for k in range(1, 14)],
}


def planner_symbols() -> dict[str, tuple[int, int]]:
    """(address, size) of planner.c's variables in the firmware ELF."""
    out = subprocess.run(["readelf", "-sW", str(FIRMWARE_ELF)], capture_output=True,
                         text=True, check=True).stdout
    symbols: dict[str, tuple[int, int]] = {}
    source = None
    for row in out.splitlines():
        f = row.split()
        if len(f) >= 8 and f[3] == "FILE":
            source = f[7]
        elif len(f) >= 8 and f[3] == "OBJECT" and source == "planner.c":
            symbols[f[7]] = (int(f[1], 16), int(f[2]))
    return symbols


@pytest.mark.parametrize("name", list(WINDOWS))
def test_block_speeds_equal_the_firmware_ones(plotter_factory, name):
    lines = ["G21", "G90", LEAD_IN, *WINDOWS[name]]
    host = received(lines).planned_blocks()
    assert 4 <= len(host) <= 15, len(host)   # all fit: every line is acknowledged
    sym = planner_symbols()
    plotter = plotter_factory(speed=1)
    board = Board(plotter.port)
    board.command("$X")
    board.stream(lines, timeout=60)       # every line acknowledged: planned

    def peek(var: str) -> bytes:
        addr, size = sym[var]
        return bytes.fromhex(plotter.control(f"peek {addr} {size}"))
    ring, tail, count = peek("ring"), peek("tail")[0], peek("count")[0]
    size = len(host[0])
    slots = len(ring) // size
    assert slots * size == len(ring)
    board.close()
    plotter.stop()
    assert count == len(host), (count, len(host))
    board_blocks = [ring[((tail + k) % slots) * size:((tail + k) % slots + 1) * size]
                    for k in range(count)]
    for k, (ours, theirs) in enumerate(zip(host, board_blocks, strict=True)):
        assert ours == theirs, f"block {k}: host {ours.hex()} board {theirs.hex()}"
