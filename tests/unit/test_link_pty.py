"""The link's real port path (pyserial + pyserial-asyncio) over an OS pseudo-terminal.

The master side plays a minimal scripted GRBL; the link opens the slave by a
symlink, as it opens plotsim's pty. Covers what the fake transport cannot:
opening, non-blocking writes, and noticing a closed port.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import time

from plotbridge.plotter.link import Link, StreamAborted

from tests.fixtures.waits import settle


class PtyBoard:
    def __init__(self) -> None:
        self.master, slave = os.openpty()
        self.slave_name = os.ttyname(slave)
        os.close(slave)
        os.set_blocking(self.master, False)
        self.rx = bytearray()
        self.lines: list[str] = []
        self.raw = bytearray()
        self.hold = False
        self.closed = False
        asyncio.get_running_loop().add_reader(self.master, self._readable)

    def _readable(self) -> None:
        try:
            data = os.read(self.master, 4096)
        except OSError:
            return
        self.raw += data
        for byte in data:
            if byte == ord("?"):
                os.write(self.master, b"<Idle|MPos:1.000,2.000,0.000|Bf:15,128|FS:0,0>\r\n")
            elif byte == 0x18:
                self.rx.clear()
                os.write(self.master, b"\r\nGrbl 1.1h ['$' for help]\r\n")
            else:
                self.rx.append(byte)
                assert len(self.rx) <= 128
        self.execute()

    def execute(self) -> None:
        while not self.hold and b"\n" in self.rx:
            end = self.rx.index(b"\n")
            line = self.rx[:end].decode()
            del self.rx[:end + 1]
            self.lines.append(line)
            answer = b"$0=4\r\n$110=6000.000\r\nok\r\n" if line == "$$" else b"ok\r\n"
            os.write(self.master, answer)

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            asyncio.get_running_loop().remove_reader(self.master)
            os.close(self.master)


async def test_pty_connect_stream_estop_and_loss(tmp_path):
    board = PtyBoard()
    port = tmp_path / "plotter.pty"
    port.symlink_to(board.slave_name)
    link = Link(str(port))
    task = asyncio.create_task(link.run())
    try:
        await settle(lambda: link.connected)
        assert link.settings == {0: 4.0, 110: 6000.0}
        assert (link.status.x, link.status.y) == (1.0, 2.0)
        assert b"\x18" not in board.raw

        acked: list[int] = []
        await link.stream(iter((n, f"G1 X{n} Y{n} F1000") for n in range(1, 501)), acked.append)
        assert acked == list(range(1, 501))

        board.hold = True
        stream = asyncio.create_task(
            link.stream(iter((n, f"G1 X{n} F1000") for n in range(1, 100)), acked.append))
        await settle(lambda: len(board.rx) > 100)
        link.estop()
        try:
            await asyncio.wait_for(stream, 2)
        except StreamAborted as exc:
            assert exc.reason == "estop"
        else:
            raise AssertionError("stream was not aborted")
        await settle(lambda: board.raw.endswith(b"\x18") or b"\x18?" in board.raw)
        board.hold = False

        board.close()
        t0 = time.monotonic()
        await settle(lambda: not link.connected, 2.0)
        assert time.monotonic() - t0 < 1.0
        assert link.status.state == "Disconnected"
    finally:
        board.close()
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
