"""The serial link (plotbridge.plotter.link) against a scripted GRBL board
(tests/fixtures/fake_board.py) standing in for the port."""

from __future__ import annotations

import asyncio
import contextlib
import re
import time

import pytest
from plotbridge.plotter.link import (
    CommandError,
    LinkDown,
    LinkEvent,
    StreamAborted,
)
from plotbridge.program.wire import compact_async

from tests.fixtures.fake_board import (
    FakeBoard,
    FakeLink,
    aiter_of,
    drain_recording,
    feed_slowly,
    program,
    running,
)
from tests.fixtures.waits import settle

# --- connecting ---------------------------------------------------------------


async def test_connect_probes_reads_settings_and_never_resets():
    board = FakeBoard()
    async with running(board) as link:
        assert link.settings == {0: 4.0, 10: 3.0, 110: 6000.0, 130: 300.0, 131: 220.0}
        assert link.status.firmware == "1.1h.20190825"
        assert link.status.connected and link.status.state == "Idle"
        assert board.lines[:2] == ["$I", "$$"]
        assert b"\x18" not in b"".join(board.writes)
        assert any(e.kind == "connected" for e in link.events)


async def test_connect_with_banner_asks_for_the_build():
    # The banner's "1.1h" does not tell stock GRBL from our firmware; `$I` does (the
    # estimate's motion model depends on it), and a later banner keeps what it told.
    board = FakeBoard(banner_on_connect=True)
    async with running(board) as link:
        assert link.status.firmware == "1.1h.20190825"
        assert board.lines == ["$I", "$$"]
        link._on_banner("1.1h")
        assert link.status.firmware == "1.1h.20190825"


async def test_connected_only_once_the_state_is_known():
    # A board that announced itself with its banner has sent no report yet: the link
    # asks for one before it says it is connected (a sender checking for Alarm at the
    # connect must not read the placeholder "Disconnected").
    board = FakeBoard(banner_on_connect=True)
    board.state = "Alarm"
    async with running(board) as link:
        kinds = [e.kind for e in link.events]
        first = link.events[kinds.index("connected") + 1]
        assert first.kind == "status" and first.status is not None
        assert first.status.connected and first.status.state == "Alarm"


async def test_no_grbl_board_is_retried_not_fatal():
    board = FakeBoard()
    board.muted = True
    link = FakeLink(board)
    task = asyncio.create_task(link.run())
    try:
        await asyncio.sleep(0.8)
        assert not link.connected and not task.done()
        board.muted = False
        await settle(lambda: link.connected, 3.0)
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


async def test_status_polled_and_published():
    board = FakeBoard()
    async with running(board) as link:
        board.state, board.pos, board.accessories = "Run", (12.0, 3.5), "S"
        await settle(lambda: link.status.state == "Run")
        assert (link.status.x, link.status.y, link.status.pen) == (12.0, 3.5, "down")
        assert link.status.planner_free == 15
        statuses = [e for e in link.events if e.kind == "status"]
        assert statuses and statuses[-1].status.state == "Run"
        assert statuses[-1].type == "status"


# --- commands -----------------------------------------------------------------


async def test_command_collects_responses():
    board = FakeBoard()
    board.script["$G"] = ["[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]", "ok"]
    async with running(board) as link:
        assert await link.command("$G") == ["[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]"]
        assert await link.command("G0 X10") == []
        tx = [e.line for e in link.events if e.kind == "log" and e.direction == "tx"]
        assert "G0 X10" in tx


async def test_homing_answer_carries_the_state_homing_left():
    board = FakeBoard()
    board.state = "Alarm"
    async with running(board) as link:
        await settle(lambda: link.status.state == "Alarm")
        link.poll_hz = 0.01     # no routine poll may refresh the state by chance

        def home(line: str) -> list[str] | None:
            if line == "$H":
                board.state = "Idle"
                return ["ok"]
            return None

        board.on_line = home
        await link.command("$H")
        assert link.status.state == "Idle"


async def test_command_error_raises_with_code_and_message():
    board = FakeBoard()
    board.script["G5"] = ["error:20"]
    async with running(board) as link:
        with pytest.raises(CommandError) as info:
            await link.command("G5")
        assert info.value.code == 20 and "unsupported" in info.value.message
        assert await link.command("G0 X1") == []   # the next ack is matched correctly


async def test_command_rejects_unsendable_line_without_sending():
    board = FakeBoard()
    async with running(board) as link:
        sent = len(board.writes)
        with pytest.raises(CommandError, match="cannot be sent"):
            await link.command("G0 X1 ~")
        assert all(b"G0 X1" not in w for w in board.writes[sent:])


async def test_command_without_link_raises_link_down():
    link = FakeLink(FakeBoard())
    with pytest.raises(LinkDown):
        await link.command("$X")
    with pytest.raises(LinkDown):
        link.realtime(b"!")


# --- streaming ----------------------------------------------------------------


async def test_stream_keeps_buffer_full_never_over_128_acks_in_order():
    board = FakeBoard(auto=False)
    async with running(board) as link:
        acked: list[int] = []
        fills: list[int] = []
        stop = asyncio.Event()

        drainer = asyncio.create_task(drain_recording(board, stop, fills))
        await link.stream(iter(program(300)), acked.append)
        stop.set()
        await drainer
        assert acked == list(range(1, 301))
        assert board.max_rx <= 128
        # Character counting keeps the buffer topped up: never just one line in it.
        busy = [f for f in fills[5:-20]]
        assert min(busy) > 128 - 2 * 40, f"buffer ran low: {min(busy)}"
        assert link._counter.outstanding == 0


async def test_stream_lines_sent_ahead_of_acks():
    board = FakeBoard(auto=False)
    async with running(board) as link:
        task = asyncio.create_task(link.stream(iter(program(20)), lambda n: None))
        await settle(lambda: len(board.rx) > 90)
        # Several lines are in the buffer while none is acknowledged yet.
        assert board.rx.count(b"\n") >= 3
        board.auto = True
        board.execute()
        await asyncio.wait_for(task, 2)


async def test_error_mid_stream_aborts_with_line_number():
    board = FakeBoard()
    board.on_line = lambda line: ["error:33"] if line.startswith("G1 X5.000 ") else None
    async with running(board) as link:
        acked: list[int] = []
        with pytest.raises(StreamAborted) as info:
            await link.stream(iter(program(40)), acked.append)
        exc = info.value
        assert exc.reason == "error" and exc.error_line == 10
        assert "error:33" in exc.message and "invalid" in exc.message
        assert acked[:9] == list(range(1, 10)) and 10 not in acked
        assert exc.last_acked == 9
        # The link stays usable and in step afterwards.
        board.on_line = None
        await settle(lambda: link._counter.outstanding == 0)
        assert await link.command("G0 X0") == []


async def test_alarm_mid_stream_aborts_and_shows_alarm():
    board = FakeBoard(auto=False)

    def limit(line: str) -> list[str] | None:
        if line.startswith("G1 X10.000 "):
            board.rx.clear()           # GRBL empties its buffers on an alarm
            board.state = "Alarm"
            return ["ALARM:2"]
        return None

    board.on_line = limit
    async with running(board) as link:
        stop = asyncio.Event()
        drainer = asyncio.create_task(feed_slowly(board, stop))
        with pytest.raises(StreamAborted) as info:
            await link.stream(iter(program(100)), lambda n: None)
        stop.set()
        await drainer
        assert info.value.reason == "alarm" and "ALARM:2" in info.value.message
        assert info.value.last_acked == 19
        assert link.status.alarm == 2
        assert any(e.kind == "alarm" and e.code == 2 for e in link.events)
        assert link._counter.outstanding == 0
        board.state = "Idle"
        await settle(lambda: link.status.state == "Idle")
        assert link.status.alarm is None


async def test_alarm_leftovers_answered_with_error_are_not_taken_for_a_command():
    # Firmware that does not empty its buffer on an alarm answers the lines
    # left in it with error:9; those answers must not reach the next command.
    board = FakeBoard(auto=False)

    def limit(line: str) -> list[str] | None:
        if board.state == "Alarm" and not line.startswith("$"):
            return ["error:9"]
        if line.startswith("G1 X10.000 "):
            board.state = "Alarm"
            return ["ALARM:1"]
        return None

    board.on_line = limit
    async with running(board) as link:
        task = asyncio.create_task(link.stream(iter(program(100)), lambda n: None))
        await settle(lambda: len(board.rx) > 90)
        while board.state != "Alarm":     # run up to the alarm; leftovers stay
            board.execute(1)
            await asyncio.sleep(0.001)
        assert board.rx.count(b"\n") >= 2
        with pytest.raises(StreamAborted):
            await asyncio.wait_for(task, 1)
        unlock = asyncio.create_task(link.command("$X"))
        await asyncio.sleep(0.05)
        assert b"$X\n" not in board.writes    # held back while leftovers are unanswered
        def unlock_or_refuse(line: str) -> list[str] | None:
            if line == "$X":
                board.state = "Idle"
                return ["ok"]
            return limit(line)

        board.on_line = unlock_or_refuse
        board.auto = True
        board.execute()                   # leftovers answered: error:9 ...
        assert await asyncio.wait_for(unlock, 1) == []
        assert board.lines[-1] == "$X" and board.state == "Idle"


async def test_stream_rejects_unsendable_line():
    board = FakeBoard()
    async with running(board) as link:
        lines = [(1, "G0 X1"), (2, "G1 X2 F100 ?"), (3, "G0 X3")]
        with pytest.raises(StreamAborted) as info:
            await link.stream(iter(lines), lambda n: None)
        assert info.value.reason == "error" and info.value.error_line == 2
        assert "G0 X3" not in board.lines


async def test_cancel_stream():
    board = FakeBoard(auto=False)
    async with running(board) as link:
        task = asyncio.create_task(link.stream(iter(program(200)), lambda n: None))
        await settle(lambda: len(board.rx) > 90)
        link.cancel_stream()
        with pytest.raises(StreamAborted) as info:
            await asyncio.wait_for(task, 1)
        assert info.value.reason == "cancelled"


async def test_garbage_from_board_is_ignored():
    board = FakeBoard()
    noisy = {"G0 X1": b"\xff\xfe\x00\x00", "G0 X2": b"x" * 5000 + b"\r\n"}

    def noise(line: str) -> list[str] | None:
        if line in noisy:
            board.send(raw=noisy[line])
        return None

    board.on_line = noise
    async with running(board) as link:
        board.send(raw=b"\x00\x00\xc3\x28\xa0\xa1 garbage \x07\r\n")
        await asyncio.sleep(0.02)
        assert await link.command("G0 X1") == []
        assert await link.command("G0 X2") == []
        acked: list[int] = []
        await link.stream(iter(program(50)), acked.append)
        assert acked == list(range(1, 51))
        assert link.connected


async def test_disconnect_mid_stream_then_reconnect():
    board = FakeBoard(auto=False)
    async with running(board) as link:
        task = asyncio.create_task(link.stream(iter(program(200)), lambda n: None))
        await settle(lambda: len(board.rx) > 90)
        board.execute(3)
        await asyncio.sleep(0.01)
        board.unplug()
        with pytest.raises(StreamAborted) as info:
            await asyncio.wait_for(task, 1)
        assert info.value.reason == "disconnected" and info.value.last_acked == 3
        await settle(lambda: not link.connected)
        assert link.status.state == "Disconnected"
        assert any(e.kind == "disconnected" for e in link.events)
        with pytest.raises(LinkDown):
            await link.command("$X")
        board.auto = True
        board.unplugged = False
        await settle(lambda: link.connected, 3.0)
        assert board.connects == 2 and board.lines.count("$$") == 2


async def test_silent_board_noticed_within_a_second():
    board = FakeBoard()
    async with running(board) as link:
        board.muted = True
        t0 = time.monotonic()
        await settle(lambda: not link.connected, 2.0)
        assert time.monotonic() - t0 < 1.0
        board.muted = False
        await settle(lambda: link.connected, 3.0)


# --- realtime and emergency stop ------------------------------------------------


async def test_estop_during_stream_writes_reset_first_and_aborts():
    board = FakeBoard(auto=False)
    board.state = "Run"
    async with running(board) as link:
        task = asyncio.create_task(link.stream(iter(program(300)), lambda n: None))
        await settle(lambda: len(board.rx) > 90)
        before = len(board.writes)
        link.estop()   # synchronous: the byte is out before estop() returns
        written = board.writes[before:]
        assert written[-1] == b"\x18"
        assert all(w in (b"<flush>", b"\x18") for w in written)
        with pytest.raises(StreamAborted) as info:
            await asyncio.wait_for(task, 1)
        assert info.value.reason == "estop"
        after = board.writes[before + len(written):]
        assert not any(w.endswith(b"\n") for w in after), "G-code sent after the reset"
        await settle(lambda: link.status.state == "Alarm")


async def test_a_stream_whose_job_was_stopped_before_it_began_sends_nothing():
    """A stop (soft reset) between a job's start and its first stream: the stream, handed
    the reset count from the job's start, ends at once; no line reaches the board."""
    board = FakeBoard()
    async with running(board) as link:
        began = link.resets
        link.estop()
        board.send("", "Grbl 1.1h ['$' for help]")
        sent = len(board.lines)
        with pytest.raises(StreamAborted) as info:
            await asyncio.wait_for(link.stream(iter(program(50)), lambda n: None, began), 1)
        assert info.value.reason == "estop"
        assert len(board.lines) == sent
        await asyncio.wait_for(link.stream(iter(program(3)), lambda n: None, link.resets), 5)
        assert len(board.lines) > sent  # a job begun after the reset streams


async def test_command_after_reset_waits_for_banner():
    board = FakeBoard()
    async with running(board) as link:
        board.muted = True              # the board is busy resetting
        link.estop()
        board.muted = False
        cmd = asyncio.create_task(link.command("$X"))
        await asyncio.sleep(0.05)
        assert "$X" not in board.lines  # held back until the banner
        board.send("ok")                # a late answer to a line from before the reset
        board.send("", "Grbl 1.1h ['$' for help]")
        assert await asyncio.wait_for(cmd, 1) == []
        assert board.lines[-1] == "$X"


async def test_realtime_bytes_written_immediately():
    board = FakeBoard(auto=False)
    async with running(board) as link:
        task = asyncio.create_task(link.stream(iter(program(100)), lambda n: None))
        await settle(lambda: len(board.rx) > 90)
        link.realtime(b"!")
        assert board.writes[-1] == b"!"
        link.realtime(b"~")
        assert board.writes[-1] == b"~"
        with pytest.raises(ValueError):
            link.realtime(b"G")
        link.cancel_stream()
        with pytest.raises(StreamAborted):
            await task


async def test_reset_to_continue_gets_a_soft_reset():
    board = FakeBoard()
    async with running(board) as link:
        alarms: list[int | None] = []
        link.subscribe(lambda event: alarms.append(event.code) if event.kind == "alarm" else None)
        board.send("ALARM:1", "[MSG:Reset to continue]")
        await settle(lambda: b"\x18" in board.writes)
        assert alarms == [1]  # (the status may already be the reset board's, without it)


async def test_subscriber_errors_do_not_break_the_link():
    board = FakeBoard()
    async with running(board) as link:
        def broken(event: LinkEvent) -> None:
            raise RuntimeError("subscriber bug")

        unsubscribe = link.subscribe(broken)
        assert await link.command("G0 X1") == []
        unsubscribe()
        assert link.connected


async def test_stock_grbl_work_position_reports_without_buffer_field():
    # A stock board with $10=0: WPos, WCO only every few reports, no Bf.
    board = FakeBoard(banner_on_connect=True)
    reports = iter(["<Idle|WPos:5.000,7.000,0.000|FS:0,0|WCO:10.000,20.000,0.000>"]
                   + ["<Run|WPos:6.000,8.000,0.000|FS:500,0>"] * 1000)
    board.status_line = lambda: next(reports)
    async with running(board) as link:
        await settle(lambda: link.status.state == "Run")
        assert (link.status.x, link.status.y) == (16.0, 28.0)
        assert link.status.rx_free is None and link.status.feed == 500
        acked: list[int] = []
        await link.stream(iter(program(60)), acked.append)
        assert acked == list(range(1, 61))


async def test_settings_follow_writes_and_rereads():
    board = FakeBoard()
    async with running(board) as link:
        await link.command("$110=4000")
        assert link.settings[110] == 4000.0
        board.script["$$"] = ["$110=4000.000", "$130=250.000", "ok"]
        await link.command("$$")
        assert link.settings == {110: 4000.0, 130: 250.0}
        board.script["$111=-5"] = ["error:4"]
        with pytest.raises(CommandError):
            await link.command("$111=-5")
        assert 111 not in link.settings


async def test_stalled_event_loop_is_not_taken_for_a_silent_board():
    board = FakeBoard()
    async with running(board) as link:
        time.sleep(link.silence_timeout * 3)  # noqa: ASYNC251 - the loop stalls on purpose
        await asyncio.sleep(0.2)
        assert link.connected
        assert not any(e.kind == "disconnected" for e in link.events)


async def test_a_board_stalled_with_the_server_gets_its_time_after_the_stall():
    # a frozen host stops the server and a simulated board alike; after it the board takes
    # a moment to answer again while the server's polls go out at once
    board = FakeBoard()
    async with running(board) as link:
        board.muted = True
        time.sleep(link.silence_timeout * 3)  # noqa: ASYNC251 - the loop stalls on purpose
        await asyncio.sleep(link.silence_timeout * 2 / 3)  # polls go out, none answered
        board.muted = False
        await asyncio.sleep(0.2)
        assert link.connected
        assert not any(e.kind == "disconnected" for e in link.events)
        # a board that stays silent is still lost
        board.muted = True
        await settle(lambda: not link.connected, what="a silent board is lost")


async def test_smaller_receive_buffer_from_build_info_is_respected():
    board = FakeBoard()
    board.script["$I"] = ["[VER:1.1h.20190825:]", "[OPT:V,15,64]", "ok"]
    board.auto = False
    async with running(board) as link:
        stop = asyncio.Event()
        drainer = asyncio.create_task(feed_slowly(board, stop))
        await link.stream(iter(program(100)), lambda n: None)
        stop.set()
        await drainer
        assert 40 < board.max_rx <= 64


async def test_lines_go_numbered_to_a_board_with_line_numbers_and_count_the_n_words():
    board = FakeBoard(auto=False)
    board.script["$I"] = ["[VER:1.1h.plotbridge:]", "[OPT:N,63,128]", "ok"]
    async with running(board) as link:
        assert link.facts.line_numbers
        fills: list[int] = []
        stop = asyncio.Event()

        async def lines():
            for item in program(300, start=99_990):  # N words of 5 to 6 digits
                yield item

        acked: list[int] = []
        drainer = asyncio.create_task(drain_recording(board, stop, fills))
        await link.stream(compact_async(lines(), link.settings, link.facts.line_numbers),
                          acked.append)
        stop.set()
        await drainer
        sent = [line for line in board.lines if line.startswith("N")]
        assert [int(re.match(r"N(\d+)", line)[1]) for line in sent] == list(range(99_990, 100_290))
        assert acked == list(range(99_990, 100_290))
        # the added bytes are counted: never over the 128 bytes, yet kept full
        assert board.max_rx <= 128
        assert min(fills[5:-20]) > 128 - 2 * 40
        assert link._counter.outstanding == 0


async def test_lines_go_unnumbered_to_a_board_without_line_numbers():
    board = FakeBoard()
    async with running(board) as link:
        assert not link.facts.line_numbers
        await link.stream(compact_async(aiter_of(program(5)), link.settings,
                                        link.facts.line_numbers), lambda n: None)
        assert board.lines[-5:] and not any(line.startswith("N") for line in board.lines)


async def test_partial_writes_are_finished_in_order():
    board = FakeBoard()
    async with running(board) as link:
        board.write_limit = 7
        acked: list[int] = []
        await link.stream(iter(program(50)), acked.append)
        assert acked == list(range(1, 51))
        assert board.lines[-50:] == [text.strip() for _, text in program(50)]
        assert board.max_rx <= 128


async def test_estop_with_full_os_buffer_discards_unsent_lines():
    board = FakeBoard(auto=False)
    async with running(board) as link:
        task = asyncio.create_task(link.stream(iter(program(200)), lambda n: None))
        await settle(lambda: len(board.rx) > 60)
        board.write_limit = 0                # the OS takes nothing for now
        board.execute(2)
        await asyncio.sleep(0.02)            # freed space: more lines queue up unsent
        assert link._backlog
        link.estop()
        board.write_limit = None
        with pytest.raises(StreamAborted):
            await asyncio.wait_for(task, 1)
        await settle(lambda: b"\x18" in board.writes)
        after = b"".join(board.writes[board.writes.index(b"\x18"):])
        assert b"G1" not in after, "line bytes reached the board after the reset"
