"""The serial link to a GRBL 1.1 board: one asyncio task owns the port.

`Link.run()` connects, identifies the board, reads its settings, polls its
status and reconnects with backoff forever. Everything else (commands,
streams, realtime bytes) goes through the port that task opened. Board lines
are handled synchronously as bytes arrive, so acknowledgements, alarms and
status reports never wait behind an await.

Only GRBL 1.1 behaviour is relied on, so stock GRBL boards work as well as
our firmware. See docs/INTERNALS.md for the seam to the job side.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import os
import time
from collections.abc import AsyncIterable, AsyncIterator, Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

import serial
import serial_asyncio

from plotbridge.grbl import (
    FEED_HOLD,
    RX_BUFFER_SIZE,
    SOFT_RESET,
    STATUS_QUERY,
    CharCounter,
    LineSplitter,
    Status,
    alarm_message,
    buffers_from_feedback,
    build_of,
    classify,
    cost,
    error_message,
    line_problem,
    option_letters,
    version_from_feedback,
)
from plotbridge.plotter.board import BoardFacts

log = logging.getLogger("plotbridge.plotter.link")

REALTIME_BYTES = frozenset(b"?!~\x18") | frozenset(range(0x80, 0x100))
STATE_CHANGING = frozenset({"$H", "$X"})  # their answer waits for the state they leave
STATUS_AFTER_S = 2.0


Lines = Iterable[tuple[int, str]] | AsyncIterable[tuple[int, str]]


class LinkDown(Exception):
    """The board is not connected (or the connection was lost while waiting)."""


class CommandError(Exception):
    """The board refused a command (`error:N`), or it could not be sent or answered."""

    def __init__(self, code: int | None, message: str) -> None:
        super().__init__(f"error:{code}: {message}" if code is not None else message)
        self.code = code
        self.message = message


class StreamAborted(Exception):
    """A stream ended early. `reason`: estop, error, alarm, disconnected or cancelled."""

    def __init__(self, reason: str, last_acked: int | None, error_line: int | None = None,
                 message: str = "") -> None:
        super().__init__(f"stream {reason}" + (f": {message}" if message else ""))
        self.reason = reason
        self.last_acked = last_acked
        self.error_line = error_line
        self.message = message


@dataclass
class MachineStatus:
    connected: bool = False
    state: str = "Disconnected"
    sub_state: int | None = None
    x: float = 0.0
    y: float = 0.0
    pen: str = "up"
    firmware: str | None = None
    alarm: int | None = None
    planner_free: int | None = None
    rx_free: int | None = None
    feed: float | None = None
    pins: str = ""
    line: int | None = None
    updated_at: float = 0.0     # time.time() of the last status report


@dataclass(frozen=True)
class LinkEvent:
    """`kind` (alias `type`): status | log | alarm | connected | disconnected.

    status events carry `status`; log events `direction` ("rx"/"tx") and `line`;
    alarm events `code` and `message`; disconnected events a `message`.
    Lines streamed by stream() and their oks are not logged (they would flood).
    """

    kind: str
    status: MachineStatus | None = None
    direction: str | None = None
    line: str | None = None
    code: int | None = None
    message: str | None = None

    @property
    def type(self) -> str:
        return self.kind


@dataclass
class _Command:
    line: str
    future: asyncio.Future[list[str]]
    responses: list[str] = field(default_factory=list)


@dataclass
class _Stream:
    on_ack: Callable[[int], None]
    last_acked: int | None = None
    in_flight: int = 0
    done: bool = False
    abort: StreamAborted | None = None

    def fail(self, reason: str, error_line: int | None = None, message: str = "") -> None:
        if self.abort is None and not self.done:
            self.abort = StreamAborted(reason, self.last_acked, error_line, message)


@dataclass
class _StreamLine:
    number: int
    stream: _Stream


class _PortProtocol(asyncio.Protocol):
    def __init__(self, link: Link) -> None:
        self.link = link
        self.transport: asyncio.BaseTransport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport

    def data_received(self, data: bytes) -> None:
        if self.link._transport is self.transport:
            self.link._on_data(data)

    def connection_lost(self, exc: Exception | None) -> None:
        if self.link._transport is self.transport:
            self.link._lose(f"port closed ({exc})" if exc else "port closed")


class Link:
    # Timings; class attributes so tests can shorten them.
    banner_wait = 0.5          # s to wait for a banner before asking with '?' (pty)
    banner_wait_serial = 2.0   # the same for a real port: DTR reset + bootloader take ~1-2 s
    handshake_timeout = 5.0    # s for the board to answer at all
    # s without a byte from the board while polling: link lost. A pulled cable closes the
    # port at once; this is for a hung board (a working one answers '?' within ms), and
    # the emergency stop does not wait for it. A virtual plotter is a process beside the
    # server, which a loaded host keeps off the CPU now and then: 0.8 s, then 2 s (a
    # clean-clone suite beside two busy processes) took one for lost, and its job with it.
    silence_timeout = 5.0
    silent_polls = 3           # ... and at least this many '?' sent since the last byte
    stall = 0.5                # s a poll came late by: this process stalled (silence restarts)
    reset_settle = 2.5         # s commands wait for the banner after a soft reset
    backoff_min = 0.5
    backoff_max = 5.0

    def __init__(self, device: str, baud: int = 115200, poll_hz: float = 8) -> None:
        self.device = device
        self.baud = baud
        self.poll_hz = poll_hz
        self.status = MachineStatus()
        self.settings: dict[int, float] = {}
        self.facts = BoardFacts()  # what the board said about itself ($I, Bf:)
        self._subscribers: list[Callable[[LinkEvent], None]] = []
        self._transport: Any = None
        self._ready = False
        self._counter = CharCounter()
        self._splitter = LineSplitter()
        self._send_lock = asyncio.Lock()
        self._wake = asyncio.Event()
        self._alive = asyncio.Event()
        # Cleared after a soft reset (until the banner) or an alarm (until the board
        # reports an empty receive buffer): late answers to lines from before must
        # not be taken for answers to new ones.
        self._settled = asyncio.Event()
        self._settled.set()
        self._await_banner = False
        self.resets = 0  # soft resets sent: a stream for a job begun before one never starts
        self._stream: _Stream | None = None
        self._lost: asyncio.Future[str] | None = None
        self._last_rx = 0.0
        self._unanswered_polls = 0
        self._wco: tuple[float, ...] = (0.0, 0.0, 0.0)
        self._settings_stale = False
        self._tasks: set[asyncio.Task[Any]] = set()
        self._real_port = False     # a real serial device (not a pty): may reset on open
        self._backlog = bytearray()  # bytes the OS did not take yet
        self._backlog_timer: asyncio.TimerHandle | None = None
        self._status_waiters: list[asyncio.Future[None]] = []

    # --- public API -------------------------------------------------------

    @property
    def connected(self) -> bool:
        return self._ready

    @property
    def awaiting_banner(self) -> bool:
        """A soft reset went out and its banner has not come: a report now is from before
        the reset (the board answers a reset with its banner first)."""
        return self._await_banner

    def subscribe(self, callback: Callable[[LinkEvent], None]) -> Callable[[], None]:
        """Call `callback` synchronously for every event; it must not block."""
        self._subscribers.append(callback)

        def unsubscribe() -> None:
            with contextlib.suppress(ValueError):
                self._subscribers.remove(callback)

        return unsubscribe

    async def run(self) -> None:
        delay = self.backoff_min
        failures = 0
        while True:
            reason = "link stopped"
            try:
                reason = await self._session()
                log.warning("link to %s lost: %s", self.device, reason)
                delay, failures = self.backoff_min, 0
            except (OSError, serial.SerialException, LinkDown, TimeoutError) as exc:
                reason = f"cannot connect: {exc}"
                failures += 1
                level = logging.WARNING if failures == 1 else logging.DEBUG
                log.log(level, "cannot connect to %s: %s (retrying)", self.device, exc)
            except Exception as exc:
                reason = f"link failed: {exc}"
                failures += 1
                log.exception("link to %s failed unexpectedly (retrying)", self.device)
            finally:
                self._end_session(reason)
            await asyncio.sleep(delay)
            delay = min(delay * 2, self.backoff_max) if failures else delay

    def realtime(self, byte: bytes) -> None:
        """Write one realtime byte to the port now, ahead of anything queued."""
        if len(byte) != 1 or byte[0] not in REALTIME_BYTES:
            raise ValueError(f"not a GRBL realtime byte: {byte!r}")
        if self._transport is None:
            raise LinkDown("not connected")
        if byte == SOFT_RESET:
            self._soft_reset("estop")
        else:
            self._write(byte, urgent=True)
            if byte != STATUS_QUERY:
                self._emit(LinkEvent("log", direction="tx", line=_show(byte)))

    def estop(self) -> None:
        """Soft reset (0x18) now; an active stream() ends with reason "estop"."""
        if self._transport is None:
            log.error("emergency stop requested with no link to the board")
            if self._stream:
                self._stream.fail("estop", message="emergency stop (board not connected)")
                self._wake.set()
            return
        self._soft_reset("estop")
        log.warning("emergency stop: soft reset sent")

    def cancel_stream(self) -> None:
        """Stop sending; the active stream() raises StreamAborted("cancelled")."""
        if self._stream:
            self._stream.fail("cancelled")
            self._wake.set()

    async def command(self, line: str, timeout: float = 10) -> list[str]:  # noqa: ASYNC109
        """Send one line and wait for its ok; returns the lines the board sent for it.

        Raises CommandError on error:N (or an alarm/reset before the answer),
        LinkDown when not connected, TimeoutError without an answer in time.
        """
        async with self._send_lock:
            await self._wait_settled()
            if not self._ready:
                raise LinkDown("not connected")
            responses = await self._exchange(line, timeout)
            if line.upper() in STATE_CHANGING:
                await self._next_status(STATUS_AFTER_S)
            return responses

    async def _next_status(self, limit_s: float) -> None:
        """Ask for a report and wait for it: a report that arrives after an `ok` was
        made after it, so the caller sees the state the command left, not a stale one."""
        waiter: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self._status_waiters.append(waiter)
        try:
            self._write(STATUS_QUERY, urgent=True)
            await asyncio.wait_for(waiter, limit_s)
        except (TimeoutError, LinkDown):
            log.warning("no status report within %.1f s of a state change", limit_s)
        finally:
            if waiter in self._status_waiters:
                self._status_waiters.remove(waiter)

    async def stream(self, lines: Lines, on_ack: Callable[[int], None],
                     resets: int | None = None) -> None:  # fmt: skip
        """Stream (line number, text) pairs with character counting.

        `lines` may be an async iterable (a program read lazily from disk).
        Keeps as many lines in the board's receive buffer as fit in its 128
        bytes, so the planner never starves; calls on_ack(number) per ok, in
        order. Returns when every line is acknowledged; raises StreamAborted,
        at once when `resets` (the count when its job began) is no longer the
        count: a stop came before the stream could begin.
        """
        async with self._send_lock:
            await self._wait_settled()
            if not self._ready:
                raise LinkDown("not connected")
            if resets is not None and resets != self.resets:
                raise StreamAborted("estop", None, message="reset before the stream began")
            st = _Stream(on_ack)
            self._stream = st
            try:
                await self._send_lines(st, lines)
                while st.abort is None and st.in_flight:
                    self._wake.clear()
                    await self._wake.wait()
                if st.abort is not None:
                    st.abort.last_acked = st.last_acked
                    raise st.abort
            finally:
                st.done = True
                self._stream = None

    # --- sending ----------------------------------------------------------

    async def _send_lines(self, st: _Stream, lines: Lines) -> None:
        async for number, raw in _aiter(lines):
            text = raw.strip()
            problem = line_problem(text)
            if problem:
                st.fail("error", number, problem)
            size = cost(text)
            while st.abort is None and not self._counter.fits(size):
                self._wake.clear()
                await self._wake.wait()
            if st.abort is not None:
                return
            self._counter.push(size, _StreamLine(number, st))
            st.in_flight += 1
            try:
                self._write(text.encode("ascii") + b"\n")
            except LinkDown as exc:
                st.fail("disconnected", message=str(exc))

    async def _exchange(self, line: str, limit_s: float) -> list[str]:
        text = line.strip()
        problem = line_problem(text)
        if problem:
            raise CommandError(None, problem)
        size = cost(text)
        # Lines of an aborted stream may still be in the board's buffer.
        async with asyncio.timeout(limit_s):
            while not self._counter.fits(size):
                if not self._ready and self._transport is None:
                    raise LinkDown("not connected")
                self._wake.clear()
                await self._wake.wait()
        cmd = _Command(text, asyncio.get_running_loop().create_future())
        self._counter.push(size, cmd)
        self._write(text.encode("ascii") + b"\n")
        self._emit(LinkEvent("log", direction="tx", line=text))
        # Shielded: on timeout the entry stays queued to absorb its late answer.
        responses = await asyncio.wait_for(asyncio.shield(cmd.future), limit_s)
        self._note_settings(text, responses)
        return responses

    def _note_settings(self, line: str, responses: list[str]) -> None:
        """Keep `settings` current: a `$$` answer replaces it, an accepted `$N=V` updates it."""
        if line == "$$":
            settings = {}
            for response in responses:
                kind, payload = classify(response)
                if kind == "setting":
                    settings[payload[0]] = payload[1]
            self.settings = settings
            self._settings_stale = False
        else:
            kind, payload = classify(line)
            if kind == "setting":
                self.settings[payload[0]] = payload[1]

    def _write(self, data: bytes, urgent: bool = False) -> None:
        """Write to the port now, without awaiting.

        pyserial-asyncio's transport.write() only writes from a later loop
        iteration, so bytes go straight to the non-blocking device. What the
        OS does not take waits in our own backlog, flushed from the loop;
        urgent bytes go ahead of that backlog.
        """
        transport = self._transport
        if transport is None or transport.is_closing():
            raise LinkDown("not connected")
        if self._backlog and not urgent:
            self._backlog += data
            return
        try:
            written = _write_some(transport.serial, data)
        except (serial.SerialException, OSError) as exc:
            self._lose(f"write failed ({exc})")
            raise LinkDown(str(exc)) from exc
        if written < len(data):
            rest = data[written:]
            if urgent:
                self._backlog[0:0] = rest
            else:
                self._backlog += rest
            self._flush_backlog_soon()

    def _flush_backlog_soon(self) -> None:
        if self._backlog_timer is None:
            loop = asyncio.get_running_loop()
            self._backlog_timer = loop.call_later(0.002, self._flush_backlog)

    def _flush_backlog(self) -> None:
        self._backlog_timer = None
        transport = self._transport
        if not self._backlog or transport is None or transport.is_closing():
            return
        try:
            written = _write_some(transport.serial, bytes(self._backlog))
        except (serial.SerialException, OSError) as exc:
            self._lose(f"write failed ({exc})")
            return
        del self._backlog[:written]
        if self._backlog:
            self._flush_backlog_soon()

    def _soft_reset(self, reason: str) -> None:
        """Drop untransmitted lines, write 0x18, then the bookkeeping (nothing
        outstanding will be answered)."""
        transport = self._transport
        # Lines not yet transmitted would reach the freshly reset board.
        self._backlog.clear()
        with contextlib.suppress(Exception):
            transport.serial.reset_output_buffer()
        try:
            self._write(SOFT_RESET, urgent=True)
        except LinkDown:
            log.error("soft reset could not be written: link down")
        self._settled.clear()
        self._await_banner = True
        self.resets += 1
        if self._stream is not None:
            # A stream cancelled before the reset stays "cancelled".
            self._stream.fail(reason, message="soft reset")
        self._flush_outstanding(reason="soft reset before the answer")
        self._emit(LinkEvent("log", direction="tx", line="0x18 (soft reset)"))

    async def _wait_settled(self) -> None:
        if not self._settled.is_set():
            try:
                async with asyncio.timeout(self.reset_settle):
                    await self._settled.wait()
            except TimeoutError:
                log.warning("board did not settle after a reset or alarm; continuing")
                self._settled.set()
                self._await_banner = False

    def _flush_outstanding(self, reason: str, down: bool = False) -> None:
        for tag in self._counter.clear():
            if isinstance(tag, _Command) and not tag.future.done():
                tag.future.set_exception(LinkDown(reason) if down else CommandError(None, reason))
            elif isinstance(tag, _StreamLine):
                tag.stream.in_flight -= 1
        self._wake.set()

    # --- receiving --------------------------------------------------------

    def _on_data(self, data: bytes) -> None:
        self._last_rx = time.monotonic()
        self._unanswered_polls = 0
        lines, problems = self._splitter.feed(data)
        for problem in problems:
            log.warning("from the board: %s", problem)
        for line in lines:
            try:
                self._on_line(line)
            except Exception:
                log.exception("could not handle board line %r", line)

    def _on_line(self, line: str) -> None:
        kind, payload = classify(line)
        if kind == "status":
            self._alive.set()
            self._apply_status(payload)
            return
        front = self._front()
        quiet = kind == "ok" and isinstance(front, _StreamLine)
        if not quiet:
            self._emit(LinkEvent("log", direction="rx", line=line))
        if kind in ("ok", "error"):
            self._on_ack(kind == "ok", payload, line)
        elif kind == "alarm":
            self._on_alarm(payload)
        elif kind == "banner":
            self._on_banner(payload)
        else:
            if kind == "feedback" and (version := version_from_feedback(payload)):
                self.status.firmware = version
            elif kind == "feedback" and (sizes := buffers_from_feedback(payload)):
                self._learn_options(*sizes, option_letters(payload) or "")
            elif kind == "msg" and payload.strip().lower() == "reset to continue":
                # Stock GRBL after a limit alarm ignores everything until reset.
                self._soft_reset("alarm")
            if isinstance(front, _Command):
                front.responses.append(line)

    def _learn_options(self, planner_blocks: int, rx_buffer: int, letters: str) -> None:
        """Count against the board's own receive buffer when it is smaller than GRBL's."""
        if self.facts.learn_options(planner_blocks, rx_buffer, letters):
            log.info("board receive buffer: %d bytes", rx_buffer)
            self._counter.capacity = self.facts.rx_buffer

    def _front(self) -> Any:
        return self._counter.peek()

    def _on_ack(self, ok: bool, code: int | None, line: str) -> None:
        try:
            tag = self._counter.ack()
        except LookupError:
            log.info("board sent %r with nothing outstanding; ignored", line)
            return
        self._wake.set()
        if isinstance(tag, _Command):
            if tag.future.done():
                return
            if ok:
                tag.future.set_result(tag.responses)
            else:
                tag.future.set_exception(CommandError(code, error_message(code)))
        elif isinstance(tag, _StreamLine):
            st = tag.stream
            st.in_flight -= 1
            if st.done:
                return
            if ok:
                st.last_acked = tag.number
                try:
                    st.on_ack(tag.number)
                except Exception:
                    log.exception("on_ack callback failed")
            else:
                log.warning("board refused line %d: error:%s %s", tag.number, code,
                            error_message(code))
                st.fail("error", tag.number, f"error:{code}: {error_message(code)}")

    def _on_alarm(self, code: int | None) -> None:
        message = f"ALARM:{code}: {alarm_message(code)}"
        log.warning("board alarm: %s", message)
        self.status.alarm = code
        self.status.state = "Alarm"
        if self._stream is not None:
            self._stream.fail("alarm", message=message)
        # GRBL empties its buffers on an alarm, so nothing outstanding will be
        # answered; other firmware answers the leftovers with error:9 instead.
        self._flush_outstanding(reason=message)
        self._settled.clear()
        self._emit(LinkEvent("alarm", code=code, message=message))
        self._emit_status()

    def _on_banner(self, version: str) -> None:
        if not (self.status.firmware or "").startswith(version + "."):   # keep the build
            self.status.firmware = version
        self._alive.set()
        expected = not self._settled.is_set()
        self._settled.set()
        self._await_banner = False
        if self._ready and not expected:
            log.warning("the board reset by itself (banner %s)", version)
            if self._stream is not None:
                self._stream.fail("disconnected", message="the board reset")
            self._flush_outstanding(reason="the board reset before answering")
            self._settings_stale = True

    def _apply_status(self, report: Status) -> None:
        s = self.status
        if report.wco is not None:
            self._wco = report.wco
        if report.mpos is not None:
            pos = report.mpos
        elif report.wpos is not None:
            pos = tuple(w + o for w, o in zip(report.wpos, self._wco, strict=False))
        else:
            pos = (s.x, s.y)
        scale = 25.4 if self.settings.get(13) == 1 else 1.0
        s.x, s.y = pos[0] * scale, pos[1] * scale
        s.state = report.state
        s.sub_state = report.sub_state
        s.pen = "down" if ("S" in report.accessories or "C" in report.accessories) else "up"
        s.planner_free = report.planner_free
        self.facts.learn_free(report.planner_free)
        s.rx_free = report.rx_free
        s.feed = report.feed
        s.pins = report.pins
        s.line = report.line
        s.updated_at = time.time()
        if report.state != "Alarm":
            s.alarm = None
        if (not self._settled.is_set() and not self._await_banner
                and report.rx_free == RX_BUFFER_SIZE and not self._counter.outstanding):
            self._settled.set()     # every line from before the alarm has been answered
        waiters, self._status_waiters = self._status_waiters, []
        for waiter in waiters:
            if not waiter.done():
                waiter.set_result(None)
        self._emit_status()

    # --- the session ------------------------------------------------------

    async def _open_port(self) -> Any:
        """Open the device; returns the transport (tests replace this)."""
        kwargs: dict[str, Any] = {"baudrate": self.baud, "timeout": 0, "write_timeout": 0}
        if self.device.startswith("/"):
            kwargs["exclusive"] = True

        def open_port() -> serial.SerialBase:
            port = serial.serial_for_url(self.device, **kwargs)
            real = os.path.realpath(self.device)
            self._real_port = real.startswith("/dev/") and not real.startswith("/dev/pts/")
            return port

        port = await asyncio.to_thread(open_port)
        loop = asyncio.get_running_loop()
        transport, _ = await serial_asyncio.connection_for_serial(
            loop, lambda: _PortProtocol(self), port)
        return transport

    async def _session(self) -> str:
        """One connection: open, identify, read settings, poll until lost."""
        loop = asyncio.get_running_loop()
        self._flush_outstanding("new connection", down=True)  # a write that failed last time
        self._splitter = LineSplitter()
        self._alive.clear()
        self._settled.set()
        self._lost = loop.create_future()
        self._transport = await self._open_port()
        self._last_rx = time.monotonic()
        await self._handshake()
        self._ready = True
        self.status.connected = True
        log.info("connected to %s: GRBL %s, state %s", self.device,
                 self.status.firmware or "?", self.status.state)
        self._emit(LinkEvent("connected"))
        self._emit_status()
        return await self._poll_until_lost()

    async def _handshake(self) -> None:
        assert self._lost is not None
        # A board reset by opening the port (DTR) announces itself; on a pty or
        # a board that was already running nothing comes, so ask. Never reset.
        wait = self.banner_wait_serial if self._real_port else self.banner_wait
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(self._alive.wait(), wait)
        deadline = time.monotonic() + self.handshake_timeout
        while not self._alive.is_set():
            if self._lost.done():
                raise LinkDown(self._lost.result())
            if time.monotonic() > deadline:
                raise LinkDown("no answer from a GRBL board")
            self._write(STATUS_QUERY, urgent=True)
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._alive.wait(), 0.5)
        if self.status.state == "Disconnected":   # alive by its banner: no report yet
            await self._next_status(STATUS_AFTER_S)
        if build_of(self.status.firmware) is None:   # the banner tells no build
            try:
                await self._exchange_or_lost("$I", 2.0)
            except (CommandError, TimeoutError) as exc:
                log.info("board did not answer $I: %s", exc)
        await self._read_settings()

    async def _exchange_or_lost(self, line: str, limit_s: float) -> list[str]:
        assert self._lost is not None
        task = asyncio.ensure_future(self._exchange(line, limit_s))
        done, _ = await asyncio.wait({task, self._lost}, return_when=asyncio.FIRST_COMPLETED)
        if task not in done:
            task.cancel()
            task.add_done_callback(lambda t: t.cancelled() or t.exception())
            raise LinkDown(self._lost.result())
        return task.result()

    async def _read_settings(self) -> None:
        try:
            await self._exchange_or_lost("$$", 3.0)
        except (CommandError, TimeoutError) as exc:
            log.warning("could not read settings ($$): %s; will retry when idle", exc)
            self._settings_stale = True

    async def _refresh_settings(self) -> None:
        async with self._send_lock:
            if self._ready:
                await self._read_settings()

    async def _poll_until_lost(self) -> str:
        assert self._lost is not None
        while not self._lost.done():
            interval = 1.0 / self.poll_hz  # the runner raises it while a job runs
            start = time.monotonic()
            with contextlib.suppress(LinkDown):
                self._write(STATUS_QUERY, urgent=True)
                self._unanswered_polls += 1
            if (self._settings_stale and not self._send_lock.locked()
                    and self.status.state in ("Idle", "Alarm")):
                self._settings_stale = False
                self._spawn(self._refresh_settings())
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(asyncio.shield(self._lost), interval)
            # Time alone is not enough: if this process stalled, the answers may
            # be waiting unread. The board must also have ignored several polls.
            now = time.monotonic()
            if now - start > interval + self.stall:
                # this process was kept off the CPU (a loaded or frozen host), and so may
                # the board have been (a simulator beside it): its silence counts from now
                self._last_rx, self._unanswered_polls = now, 0
            silence = now - self._last_rx
            if (silence > self.silence_timeout and self._unanswered_polls >= self.silent_polls
                    and not self._slow_command_pending()):
                self._lose(f"no answer from the board for {silence:.1f} s")
        return self._lost.result()

    def _slow_command_pending(self) -> bool:
        """Homing and EEPROM commands may keep a stock board from reporting."""
        front = self._front()
        return isinstance(front, _Command) and front.line.startswith("$")

    def _lose(self, reason: str) -> None:
        if self._lost is not None and not self._lost.done():
            self._lost.set_result(reason)

    def _end_session(self, reason: str) -> None:
        transport, self._transport = self._transport, None
        was_ready, self._ready = self._ready, False
        self._backlog.clear()
        if transport is not None:
            with contextlib.suppress(Exception):
                transport.abort()
        if self._stream is not None:
            self._stream.fail("disconnected", message=reason)
        self._flush_outstanding(reason=reason, down=True)
        self._settled.set()
        self._await_banner = False
        firmware = self.status.firmware
        self.status = MachineStatus(firmware=firmware, updated_at=time.time())
        if was_ready:
            self._emit(LinkEvent("disconnected", message=reason))
            self._emit_status()

    def _spawn(self, coro: Any) -> None:
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    # --- events -----------------------------------------------------------

    def _emit_status(self) -> None:
        self._emit(LinkEvent("status", status=dataclasses.replace(self.status)))

    def _emit(self, event: LinkEvent) -> None:
        for callback in list(self._subscribers):
            try:
                callback(event)
            except Exception:
                log.exception("link subscriber failed on %s event", event.kind)


def _aiter(lines: Lines) -> AsyncIterator[tuple[int, str]]:
    return aiter(lines) if isinstance(lines, AsyncIterable) else _from_sync(lines)


async def _from_sync(lines: Iterable[tuple[int, str]]) -> AsyncIterator[tuple[int, str]]:
    for item in lines:
        yield item


def _write_some(port: Any, data: bytes) -> int:
    """Write what the OS takes now; returns the count (0 when its buffer is full).

    pyserial's own write() retries a full non-blocking buffer in a busy loop,
    which would freeze the event loop while a peer is not reading.
    """
    fd = getattr(port, "fd", None)
    if isinstance(fd, int):
        try:
            return os.write(fd, data)
        except BlockingIOError:
            return 0
    return port.write(data) or 0


def _show(byte: bytes) -> str:
    if byte == FEED_HOLD:
        return "! (feed hold)"
    if byte == b"~":
        return "~ (cycle start)"
    return f"0x{byte[0]:02x}"
