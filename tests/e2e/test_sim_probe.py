"""plotsim against its probe test firmware, whose pin activity is known.

The probe (firmware/sim/testfw/probe.c) draws (0,0) -> (10,0) -> (10,5) at
power-up with 10 us step pulses at 10 kHz, then answers one-byte commands on
the serial port (see its header comment).
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
import serial

from tests.fixtures.plotsim import REPO, Plotter, PlotterFactory, SimBuild

pytestmark = pytest.mark.e2e

BYTE_TIME = 10 / 115200  # s per 8N1 byte


def drawn(trace: dict[str, Any]) -> bool:
    """The probe's power-up drawing is finished (pen lifted after the moves)."""
    return trace["pen_lifts"] == 1


@pytest.fixture
def probe(plotter_factory: PlotterFactory, sim_build: SimBuild) -> Plotter:
    return plotter_factory(firmware=sim_build.probe)


def open_port(plotter: Plotter) -> serial.Serial:
    port = serial.Serial(plotter.port, 115200, timeout=5)
    plotter.wait_trace(drawn)
    return port


def ask(port: serial.Serial, command: bytes) -> bytes:
    port.write(command)
    return port.readline()


def xy(stroke: list[list[float]]) -> list[tuple[float, float]]:
    return [(round(p[0], 4), round(p[1], 4)) for p in stroke]


def test_known_pin_activity_gives_known_trace(probe: Plotter) -> None:
    trace = probe.wait_trace(drawn)
    assert len(trace["strokes"]) == 1
    stroke = trace["strokes"][0]
    assert xy(stroke) == [(0.0, 0.0), (10.0, 0.0), (10.0, 5.0)]
    t = [p[2] for p in stroke]
    # pen down, an 18 ms servo gap, then 800 and 400 steps of ~107 us each
    # (5 + 10 + 90 us of delays plus loop overhead)
    assert 0.018 + 0.084 < t[1] - t[0] < 0.018 + 0.088
    assert 0.042 < t[2] - t[1] < 0.044
    assert trace["position"] == {"x": 10.0, "y": 5.0}
    assert trace["steps"] == {"x": 800, "y": 400}
    assert trace["pulses"] == {"x": 800, "y": 400}
    assert trace["pen"] == "up"
    assert trace["pen_us"] == pytest.approx(1000, abs=1)
    assert trace["draw_mm"] == pytest.approx(15.0)
    assert trace["travel_mm"] == 0
    assert trace["enabled"] is True
    assert trace["violations"] == {
        "short_pulse": 0, "dir_setup": 0, "step_while_disabled": 0, "overspeed": 0,
    }  # fmt: skip
    assert 10.0 <= trace["min_pulse_us"] < 10.6
    for axis in "xy":
        assert 9000 < trace["max_step_rate"][axis] < 10000
    assert trace["limits"] == {"x": False, "y": False}
    assert trace["sim_time"] > t[2]
    assert 0 < trace["last_step_monotonic"] <= time.monotonic()


def test_trace_file_and_svg_match(probe: Plotter, tmp_path: Path) -> None:
    trace = probe.wait_trace(drawn)
    # the file is rewritten at most 20 times a second: give it a moment
    deadline = time.monotonic() + 2
    while json.loads(probe.trace_path.read_text())["pen_lifts"] != 1:
        assert time.monotonic() < deadline, "trace file not updated"
        time.sleep(0.02)
    from_file = json.loads(probe.trace_path.read_text())
    assert from_file["strokes"] == trace["strokes"]
    svg = tmp_path / "drawn.svg"
    probe.svg(svg)
    text = svg.read_text()
    assert '<polyline points="0.000,0.000 10.000,0.000 10.000,5.000"/>' in text
    assert 'viewBox="0 0 300.000 220.000"' in text


def test_corexy_kinematics(plotter_factory: PlotterFactory, sim_build: SimBuild) -> None:
    # motor a: 800 steps +, motor b: 400 steps +; x = (a+b)/2, y = (a-b)/2
    p = plotter_factory(firmware=sim_build.probe, args=["--corexy"])
    trace = p.wait_trace(drawn)
    assert xy(trace["strokes"][0]) == [(0.0, 0.0), (5.0, 5.0), (7.5, 2.5)]
    assert trace["position"] == {"x": 7.5, "y": 2.5}


def test_pty_carries_bytes_both_ways(probe: Plotter) -> None:
    port = open_port(probe)
    commands = b"?XxYyPZDEFWR"
    data = bytes(b for b in range(256) if b not in commands) * 2
    before = probe.trace()["sim_time"]
    port.write(data)
    assert port.read(len(data)) == data
    # unthrottled, yet the bytes took their time on the simulated wire
    assert probe.trace()["sim_time"] - before > len(data) * BYTE_TIME
    assert ask(port, b"?") == b"S00000\n"


def test_byte_timing_follows_115200_in_real_time(
    plotter_factory: PlotterFactory, sim_build: SimBuild
) -> None:
    p = plotter_factory(firmware=sim_build.probe, speed=1)
    port = open_port(p)
    data = b"U" * 1000
    began, queued = time.monotonic(), p.cpu_wait()
    port.write(data)
    assert port.read(len(data)) == data
    took = time.monotonic() - began
    # A simulator kept off the CPU catches up with the wall clock afterwards (by design:
    # paced time stays true on average), so bytes may come faster by that much.
    starved = p.cpu_wait() - queued
    assert len(data) * BYTE_TIME * 0.95 - starved < took < len(data) * BYTE_TIME * 10


def test_speed_paces_simulated_time(plotter_factory: PlotterFactory, sim_build: SimBuild) -> None:
    rates, starved = {}, {}
    for speed in (1, 2, 0):
        p = plotter_factory(firmware=sim_build.probe, speed=speed)
        t0, w0, q0 = p.trace()["sim_time"], time.monotonic(), p.cpu_wait()
        time.sleep(0.5)
        t1, w1, q1 = p.trace()["sim_time"], time.monotonic(), p.cpu_wait()
        rates[speed] = (t1 - t0) / (w1 - w0)
        starved[speed] = (q1 - q0) / (w1 - w0)
        p.stop()
    # paced runs never run ahead of the wall clock
    assert rates[1] < 1.1 and rates[2] < 2.2, rates
    # and keep up with it, unless the host kept them waiting for a CPU (the suite
    # shares 2 cores): a pacer that sleeps too much falls behind without waiting
    for speed in (1, 2):
        assert rates[speed] > 0.8 * speed or starved[speed] > 0.1, (rates, starved)
    # unthrottled: ahead of the wall clock, which a paced run never is (how far ahead
    # depends on what else the host runs)
    assert rates[0] > 1.1 or starved[0] > 0.1, (rates, starved)


def test_limit_switch_closes_past_the_edge(
    plotter_factory: PlotterFactory, sim_build: SimBuild
) -> None:
    p = plotter_factory(firmware=sim_build.probe, args=["--width", "10", "--height", "5"])
    port = open_port(p)
    # the power-up drawing ends at exactly (10, 5): on the edge, switches open
    assert ask(port, b"?") == b"S00000\n"
    assert p.trace()["limits"] == {"x": False, "y": False}
    assert ask(port, b"X") == b"S00010\n"
    assert p.trace()["limits"] == {"x": True, "y": False}
    assert ask(port, b"Y") == b"S00011\n"
    assert ask(port, b"x") == b"S00001\n"
    assert ask(port, b"y") == b"S00000\n"
    assert p.trace()["limits"] == {"x": False, "y": False}


def test_limit_switch_at_zero(plotter_factory: PlotterFactory, sim_build: SimBuild) -> None:
    p = plotter_factory(firmware=sim_build.probe, start=(0, 5))
    port = open_port(p)
    # drawing from (0,5) ends at (10,10); walk X back to exactly 0 and past it
    p.press("pause")  # unrelated button: must not disturb the switches
    p.release("pause")
    for _ in range(800):
        port.write(b"x")
    replies = [port.readline() for _ in range(800)]
    assert replies[-1] == b"S00000\n"
    assert p.trace()["position"]["x"] == 0.0
    assert ask(port, b"x") == b"S00010\n"
    assert ask(port, b"X") == b"S00000\n"


def test_buttons_reach_the_firmware(probe: Plotter) -> None:
    port = open_port(probe)
    expected = {"estop": b"S10000\n", "pause": b"S01000\n", "resume": b"S00100\n"}
    for name, line in expected.items():
        probe.press(name)
        assert ask(port, b"?") == line
        assert probe.trace()["buttons"][name] is True
        probe.release(name)
        assert ask(port, b"?") == b"S00000\n"
    # the probe lights the stop LED (A3) while the stop button is held
    probe.press("estop")
    probe.wait_trace(lambda t: t["led"] is True, timeout=2)
    probe.release("estop")
    probe.wait_trace(lambda t: t["led"] is False, timeout=2)


def test_driver_checks_count_violations(probe: Plotter) -> None:
    port = open_port(probe)
    probe.clear()
    cleared = probe.trace()
    assert cleared["strokes"] == [] and cleared["pen_lifts"] == 0
    assert cleared["min_pulse_us"] is None
    assert ask(port, b"P") == b"S00000\n"  # a 2-cycle step pulse
    assert ask(port, b"Z") == b"S00000\n"  # dir flipped in the same write as the step
    assert ask(port, b"D") == b"S00000\n"  # drivers off
    before = probe.trace()["position"]
    assert ask(port, b"X") == b"S00000\n"
    trace = probe.trace()
    assert trace["enabled"] is False
    assert trace["position"] == before  # a disabled driver does not move
    assert trace["violations"] == {
        "short_pulse": 1, "dir_setup": 1, "step_while_disabled": 1, "overspeed": 0,
    }  # fmt: skip
    assert trace["min_pulse_us"] == pytest.approx(2 / 16, abs=0.07)


def test_overspeed_against_the_configured_maximum(
    plotter_factory: PlotterFactory, sim_build: SimBuild
) -> None:
    p = plotter_factory(firmware=sim_build.probe, args=["--max-step-rate", "5000"])
    trace = p.wait_trace(drawn)
    # every step interval but the first of each axis is ~107 us (9.3 kHz)
    assert trace["violations"]["overspeed"] == 799 + 399


def test_control_socket_rejects_bad_commands(probe: Plotter) -> None:
    assert probe.control("press nothing").startswith("error: unknown button 'nothing'")
    assert probe.control("fly").startswith("error: unknown command 'fly'")
    assert probe.control("svg").startswith("error: svg needs a PATH")
    assert probe.control("svg /nonexistent/dir/x.svg").startswith("error: cannot write")
    assert probe.control("trace").startswith("{")


def test_eeprom_persists_across_restart(probe: Plotter) -> None:
    port = open_port(probe)
    assert ask(port, b"W") == b"W00\n"  # blank EEPROM reads 0xFF
    port.close()
    probe.restart(start=(20, 30))
    port = open_port(probe)
    assert ask(port, b"W") == b"W01\n"
    assert probe.trace()["position"] == {"x": 30.0, "y": 35.0}
    deadline = time.monotonic() + 2  # saved on change within a fraction of a second
    while probe.eeprom_path.read_bytes()[:1] != b"\x01":
        assert time.monotonic() < deadline, "EEPROM change not saved"
        time.sleep(0.02)


def test_sigterm_cleans_up(probe: Plotter) -> None:
    port = open_port(probe)
    assert ask(port, b"W") == b"W00\n"
    pid = probe.proc.pid
    assert probe.stop() == 0
    assert not os.path.lexists(probe.port)
    assert not probe.control_path.exists()
    assert not Path(f"/proc/{pid}").exists()
    final = json.loads(probe.trace_path.read_text())
    assert final["position"] == {"x": 10.0, "y": 5.0}
    assert probe.eeprom_path.read_bytes()[:1] == b"\x00"
    assert len(probe.eeprom_path.read_bytes()) == 1024
    assert list(probe.dir.glob("*.tmp")) == []


def test_kill_then_restart_reuses_the_port(probe: Plotter) -> None:
    probe.wait_trace(drawn)
    probe.kill()
    probe.restart()
    port = open_port(probe)
    assert ask(port, b"?") == b"S00000\n"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--speed", "fast"], "--speed: invalid value 'fast'"),
        (["--start", "1"], "--start: invalid value '1'"),
        (["--bogus"], "unknown or incomplete option '--bogus'"),
        (["--pen-up-us", "1500", "--pen-down-us", "1500"], "must differ"),
        ([], "missing FIRMWARE.elf"),
        (["/nonexistent.elf"], "/nonexistent.elf: No such file or directory"),
    ],
)
def test_cli_rejects_bad_arguments(sim_build: SimBuild, args: list[str], message: str) -> None:
    result = subprocess.run(
        [str(sim_build.plotsim), *args], capture_output=True, text=True, timeout=10
    )
    assert result.returncode == 2
    assert message in result.stderr


def test_cli_rejects_a_bad_eeprom_image(sim_build: SimBuild, tmp_path: Path) -> None:
    image = tmp_path / "short.bin"
    image.write_bytes(b"\x00" * 100)
    result = subprocess.run(
        [str(sim_build.plotsim), "--eeprom", str(image), str(sim_build.probe)],
        capture_output=True, text=True, timeout=10,
    )  # fmt: skip
    assert result.returncode == 2
    assert "expected 1024 bytes" in result.stderr


def test_watchdog_reset_keeps_pins_and_serial(probe: Plotter) -> None:
    port = open_port(probe)
    probe.press("pause")
    port.write(b"R")  # watchdog reset: the probe starts over and draws again
    trace = probe.wait_trace(lambda t: t["pen_lifts"] == 2)
    assert trace["position"] == {"x": 20.0, "y": 10.0}
    # after the reset the pins read as they are (pull-ups, the held button)
    # and the serial link still carries bytes both ways
    assert ask(port, b"?") == b"S01000\n"
    probe.release("pause")
    assert ask(port, b"?") == b"S00000\n"


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"hello\n", "not an ELF file"),
        (Path(sys.executable).resolve().read_bytes()[:4096], "not an ELF file"),  # 64-bit
        (b"\x7fELF\x01\x01\x01" + bytes(9) + b"\x02\x00\x03\x00" + bytes(100), "not AVR"),
        (b"\x7fELF\x01\x01\x01" + bytes(9) + b"\x02\x00\x53\x00" + bytes(100), "no program"),
    ],
)
def test_cli_rejects_files_that_are_no_avr_program(
    sim_build: SimBuild, tmp_path: Path, content: bytes, message: str
) -> None:
    elf = tmp_path / "firmware.elf"
    elf.write_bytes(content)
    result = subprocess.run(
        [str(sim_build.plotsim), str(elf)], capture_output=True, text=True, timeout=10
    )
    assert result.returncode == 2
    assert message in result.stderr


def test_quit_command_exits_cleanly(probe: Plotter) -> None:
    assert probe.control("quit") == "ok"
    assert probe.proc.wait(timeout=5) == 0
    assert not os.path.lexists(probe.port)
    assert json.loads(probe.trace_path.read_text())["sim_time"] > 0


def test_plotsim_dies_with_the_test_process(sim_build: SimBuild, tmp_path: Path) -> None:
    script = (
        "import sys, time\n"
        "from pathlib import Path\n"
        "from tests.fixtures.plotsim import Plotter\n"
        f"p = Plotter(Path({str(sim_build.plotsim)!r}), Path({str(sim_build.probe)!r}),"
        f" Path({str(tmp_path / 'ee.bin')!r})).start()\n"
        "print(p.proc.pid, flush=True)\n"
        "time.sleep(60)\n"
    )
    parent = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, text=True, cwd=REPO
    )
    try:
        pid = int(parent.stdout.readline())
        assert Path(f"/proc/{pid}").exists()
    finally:
        parent.kill()
        parent.wait(timeout=10)
    deadline = time.monotonic() + 5
    while True:
        try:
            status = Path(f"/proc/{pid}/status").read_text()
        except FileNotFoundError:
            break  # gone
        if status.split("State:")[1].split()[0] == "Z":  # exited, not yet reaped
            break
        assert time.monotonic() < deadline, "plotsim outlived the process that started it"
        time.sleep(0.05)


def test_control_socket_pipelined_and_oversized_lines(probe: Plotter) -> None:
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
        sock.settimeout(5)
        sock.connect(str(probe.control_path))
        sock.sendall(b"press pause\r\nrelease pause\nclear\n")
        reader = sock.makefile("rb")
        assert [reader.readline() for _ in range(3)] == [b"ok\n"] * 3
        sock.sendall(b"x" * 5000 + b"\n")
        assert reader.readline() == b"error: line too long\n"
        sock.sendall(b"release estop\n")  # the connection goes on after the long line
        assert reader.readline() == b"ok\n"
