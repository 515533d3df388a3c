"""The virtual plotter: the real firmware in `plotsim` (simavr), run as a child process.

`VirtualPlotter` builds firmware and simulator with make (make decides what
is stale) for a board that is one of the profiles (checked before make runs),
starts plotsim with its pty, trace, control socket and EEPROM in the data
directory, restarts it with backoff if it dies, and stops it on shutdown. The
serial link opens `.port` like any other serial device.
"""

from __future__ import annotations

import asyncio
import contextlib
import ctypes
import json
import logging
import signal
import socket
import tempfile
import time
from pathlib import Path
from typing import Any

from plotbridge.profiles import DEFAULT_BOARD, check_board, firmware_dir

__all__ = ["VirtualPlotter", "control_request", "die_with_parent", "firmware_dir"]

log = logging.getLogger("plotbridge.virtual")


def control_request(path: Path, command: str, limit_s: float) -> str:
    """One command to a plotsim control socket and its one-line answer (blocking)."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
        sock.settimeout(limit_s)
        sock.connect(str(path))
        sock.sendall(command.encode() + b"\n")
        answer = bytearray()
        while not answer.endswith(b"\n"):
            chunk = sock.recv(65536)
            if not chunk:
                break
            answer += chunk
    return answer.decode(errors="replace").strip()


def die_with_parent() -> None:
    """In the child (preexec_fn): get SIGTERM when the parent dies, even by SIGKILL (Linux)."""
    with contextlib.suppress(Exception):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


class VirtualPlotter:
    start_timeout = 30.0       # s for plotsim to report ready
    backoff_min = 0.5
    backoff_max = 5.0

    def __init__(self, data_dir: Path, speed: float = 1.0, firmware: Path | None = None,
                 extra_args: list[str] | None = None, board: str = DEFAULT_BOARD) -> None:
        self.firmware_dir = firmware or firmware_dir()
        self.board = check_board(board, self.firmware_dir)  # UnknownBoard before any make
        self.data_dir = Path(data_dir)
        self.speed = speed
        self.extra_args = list(extra_args or [])
        self.port = self.data_dir / "plotter.pty"
        self.trace_path = self.data_dir / "trace.json"
        self.control_path = self.data_dir / "control.sock"
        if len(str(self.control_path)) > 100:  # Unix socket paths are limited to 107 bytes
            self.control_path = Path(tempfile.mkdtemp(prefix="plotbridge-")) / "control.sock"
        self.eeprom_path = self.data_dir / "eeprom.bin"
        build = "build" if board == DEFAULT_BOARD else f"build/{board}"  # firmware/Makefile
        self.elf = self.firmware_dir / build / "plotbridge.elf"
        self.plotsim = self.firmware_dir / "sim" / "build" / "plotsim"
        self._proc: asyncio.subprocess.Process | None = None
        self._supervisor: asyncio.Task[None] | None = None
        self._ready = asyncio.Event()
        self._stopping = False
        self.restarts = 0

    async def build(self) -> None:
        """`make -C firmware all sim`; a failed build is fatal only without binaries."""
        try:
            proc = await asyncio.create_subprocess_exec(
                "make", "-C", str(self.firmware_dir), f"BOARD={self.board}", "all", "sim",
                stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.STDOUT)
            output, _ = await proc.communicate()
            failed = proc.returncode != 0
            detail = output.decode(errors="replace").strip().splitlines()[-15:]
        except FileNotFoundError:
            failed, detail = True, ["make is not installed"]
        if failed:
            if self.elf.exists() and self.plotsim.exists():
                log.warning("building the virtual plotter failed; using the existing build:\n%s",
                            "\n".join(detail))
            else:
                raise RuntimeError("cannot build the virtual plotter (make -C "
                                   f"{self.firmware_dir} all sim):\n" + "\n".join(detail))

    async def start(self) -> None:
        """Build, start plotsim, and return once its pty is ready."""
        self.data_dir.mkdir(parents=True, exist_ok=True)
        await self.build()
        self._stopping = False
        self._ready.clear()
        self._supervisor = asyncio.create_task(self._supervise(), name="plotsim")
        ready = asyncio.create_task(self._ready.wait())
        done, _ = await asyncio.wait({ready, self._supervisor}, timeout=self.start_timeout,
                                     return_when=asyncio.FIRST_COMPLETED)
        if ready not in done:
            ready.cancel()
            await self.stop()
            raise RuntimeError(f"plotsim did not become ready within {self.start_timeout:g} s")

    async def stop(self) -> None:
        self._stopping = True
        await self._terminate()
        if self._supervisor is not None:
            self._supervisor.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._supervisor
            self._supervisor = None

    def command_line(self) -> list[str]:
        return [str(self.plotsim), "--pty-link", str(self.port), "--speed", f"{self.speed:g}",
                "--trace", str(self.trace_path), "--control", str(self.control_path),
                "--eeprom", str(self.eeprom_path), "--board", self.board, *self.extra_args,
                str(self.elf)]

    async def _supervise(self) -> None:
        delay = self.backoff_min
        while not self._stopping:
            started = time.monotonic()
            try:
                rc = await self._run_once()
            except OSError as exc:
                rc = None
                log.error("cannot start plotsim: %s", exc)
            if self._stopping:
                return
            if time.monotonic() - started > 10:
                delay = self.backoff_min
            log.warning("plotsim exited (%s); restarting in %.1f s", rc, delay)
            await asyncio.sleep(delay)
            delay = min(delay * 2, self.backoff_max)
            self.restarts += 1

    async def _run_once(self) -> int | None:
        proc = await asyncio.create_subprocess_exec(
            *self.command_line(), stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.STDOUT, start_new_session=True,
            preexec_fn=die_with_parent)
        self._proc = proc
        assert proc.stdout is not None
        try:
            async for raw in proc.stdout:
                line = raw.decode(errors="replace").rstrip()
                if line == "plotsim: ready":
                    log.info("virtual plotter ready on %s", self.port)
                    self._ready.set()
                elif line:
                    log.debug("%s", line)
            return await proc.wait()
        finally:
            self._proc = None

    async def _terminate(self) -> None:
        proc = self._proc
        if proc is None or proc.returncode is not None:
            return
        with contextlib.suppress(ProcessLookupError):
            proc.send_signal(signal.SIGTERM)
        try:
            await asyncio.wait_for(proc.wait(), 5)
        except TimeoutError:
            log.warning("plotsim ignored SIGTERM; killing it")
            with contextlib.suppress(ProcessLookupError):
                proc.kill()
            await proc.wait()

    @property
    def pid(self) -> int | None:
        return self._proc.pid if self._proc else None

    def control(self, command: str, limit_s: float = 2.0) -> str:
        """Send one control-socket command; returns its one-line answer (blocking)."""
        return control_request(self.control_path, command, limit_s)

    def trace(self) -> dict[str, Any]:
        """The simulator's trace JSON (blocking: call it in a thread).

        Asks the running simulator first (freshest); falls back to the trace
        file it rewrites, e.g. while it restarts.
        """
        with contextlib.suppress(OSError, ValueError):
            answer = self.control("trace")
            if answer.startswith("{"):
                return json.loads(answer)
        return json.loads(self.trace_path.read_text())
