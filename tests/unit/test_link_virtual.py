"""VirtualPlotter supervision (plotbridge.virtual) with a stand-in plotsim.

The stand-in speaks plotsim's process contract (INTERNALS.md): prints ready,
serves `trace` on the control socket, writes the trace file, exits on
SIGTERM. The real simulator is exercised by tests/e2e/test_link.py.
"""

from __future__ import annotations

import asyncio
import json
import os
import signal
import sys
import textwrap
from pathlib import Path

import pytest
from plotbridge.virtual import VirtualPlotter, firmware_dir

FAKE_PLOTSIM = textwrap.dedent("""\
    #!{python}
    import json, os, signal, socket, sys, time
    args = sys.argv[1:]
    opt = {{args[i]: args[i + 1] for i in range(0, len(args) - 1, 2)}}
    with open(opt["--trace"], "w") as f:
        json.dump({{"source": "file", "argv": args}}, f)
    starts = os.path.join(os.path.dirname(opt["--trace"]), "starts")
    with open(starts, "a") as f:
        f.write("x")
    if os.path.exists(opt["--control"]):
        os.unlink(opt["--control"])
    srv = socket.socket(socket.AF_UNIX)
    srv.bind(opt["--control"])
    srv.listen()
    signal.signal(signal.SIGTERM, lambda *a: sys.exit(0))
    print("plotsim: pty /dev/pts/99", flush=True)
    print("plotsim: ready", flush=True)
    if os.environ.get("FAKE_DIE_AFTER"):
        time.sleep(float(os.environ["FAKE_DIE_AFTER"]))
        sys.exit(3)
    while True:
        conn, _ = srv.accept()
        if conn.recv(100).strip() == b"trace":
            conn.sendall(json.dumps({{"source": "socket", "pid": os.getpid()}}).encode() + b"\\n")
        conn.close()
""")


@pytest.fixture
def fake_firmware(tmp_path: Path) -> Path:
    fw = tmp_path / "firmware"
    (fw / "build").mkdir(parents=True)
    (fw / "sim" / "build").mkdir(parents=True)
    (fw / "src" / "boards").mkdir(parents=True)
    (fw / "src" / "boards" / "uno-cnc-shield.h").write_text("/* the profile */\n")
    (fw / "Makefile").write_text(
        ".PHONY: all sim\nall:\n\ttouch made-all\nsim:\n\ttouch made-sim\n")
    (fw / "build" / "plotbridge.elf").write_bytes(b"\x7fELF")
    plotsim = fw / "sim" / "build" / "plotsim"
    plotsim.write_text(FAKE_PLOTSIM.format(python=sys.executable))
    plotsim.chmod(0o755)
    return fw


def test_firmware_dir_default_and_override(monkeypatch, tmp_path):
    monkeypatch.delenv("PLOTBRIDGE_FIRMWARE_DIR", raising=False)
    assert firmware_dir() == Path(__file__).resolve().parents[2] / "firmware"
    monkeypatch.setenv("PLOTBRIDGE_FIRMWARE_DIR", str(tmp_path))
    assert firmware_dir() == tmp_path.resolve()


async def test_start_builds_runs_and_stops(fake_firmware, tmp_path):
    vp = VirtualPlotter(tmp_path / "data", speed=4, firmware=fake_firmware)
    await vp.start()
    try:
        assert (fake_firmware / "made-all").exists() and (fake_firmware / "made-sim").exists()
        trace = await asyncio.to_thread(vp.trace)
        assert trace["source"] == "socket" and trace["pid"] == vp.pid
        argv = json.loads(vp.trace_path.read_text())["argv"]
        assert argv[argv.index("--speed") + 1] == "4"
        assert argv[argv.index("--pty-link") + 1] == str(vp.port)
        assert argv[argv.index("--eeprom") + 1] == str(tmp_path / "data" / "eeprom.bin")
        assert argv[-1] == str(fake_firmware / "build" / "plotbridge.elf")
        pid = vp.pid
    finally:
        await vp.stop()
    assert vp.pid is None
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)


async def test_restarts_after_crash(fake_firmware, tmp_path, monkeypatch):
    monkeypatch.setenv("FAKE_DIE_AFTER", "0.1")
    vp = VirtualPlotter(tmp_path / "data", firmware=fake_firmware)
    vp.backoff_min = 0.05
    await vp.start()
    try:
        starts = tmp_path / "data" / "starts"
        for _ in range(100):
            if len(starts.read_text()) >= 3:
                break
            await asyncio.sleep(0.05)
        assert len(starts.read_text()) >= 3 and vp.restarts >= 2
    finally:
        await vp.stop()


async def test_trace_falls_back_to_file(fake_firmware, tmp_path):
    vp = VirtualPlotter(tmp_path / "data", firmware=fake_firmware)
    await vp.start()
    os.kill(vp.pid, signal.SIGSTOP)   # socket accepts nothing now
    try:
        vp.control_path.unlink()
        assert (await asyncio.to_thread(vp.trace))["source"] == "file"
    finally:
        os.kill(vp.pid, signal.SIGCONT)
        await vp.stop()


async def test_build_failure_without_binaries_is_a_clear_error(tmp_path):
    fw = tmp_path / "firmware"
    (fw / "src" / "boards").mkdir(parents=True)
    (fw / "src" / "boards" / "uno-cnc-shield.h").write_text("/* the profile */\n")
    (fw / "Makefile").write_text("all:\n\t@echo 'avr-gcc: not found' && false\nsim:\n")
    vp = VirtualPlotter(tmp_path / "data", firmware=fw)
    with pytest.raises(RuntimeError, match="avr-gcc: not found"):
        await vp.start()


def test_long_data_dir_gets_a_short_control_socket(tmp_path):
    vp = VirtualPlotter(tmp_path / ("d" * 120), firmware=firmware_dir())
    assert len(str(vp.control_path)) < 100
    vp.control_path.parent.rmdir()
