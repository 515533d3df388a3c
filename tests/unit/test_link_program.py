"""Streaming a program from disk: read lazily, a bounded number of lines ahead."""

from __future__ import annotations

import asyncio
import contextlib
import threading
import tracemalloc
from pathlib import Path

import pytest
from plotbridge.plotter.link import StreamAborted
from plotbridge.program.reader import ProgramReader, motion_flags

from tests.fixtures.fake_board import FakeBoard, feed_slowly, running


def write_program(path: Path, count: int) -> list[str]:
    lines = [
        "M5" if n % 50 == 0 else f"G1 X{n % 300}.125 Y{(n * 7) % 220}.250 F3000"
        for n in range(1, count + 1)
    ]
    path.write_text("\n".join(lines) + "\n")
    return lines


async def collect(reader: ProgramReader) -> list[tuple[int, str]]:
    return [item async for item in reader.lines()]


async def test_reads_every_line_numbered_after_the_preamble(tmp_path):
    lines = write_program(tmp_path / "p.gcode", 1000)
    reader = ProgramReader(tmp_path / "p.gcode", preamble=["M5", "G21"], block_lines=64)
    got = await collect(reader)
    assert got[:2] == [(0, "M5"), (0, "G21")]
    assert got[2:] == list(enumerate(lines, 1))
    assert reader.motion == motion_flags(lines)
    assert 64 <= reader.max_held <= 128 and reader.held == 0


async def test_starts_at_any_line_and_flags_the_skipped_ones(tmp_path):
    lines = write_program(tmp_path / "p.gcode", 1000)
    reader = ProgramReader(tmp_path / "p.gcode", start=777, preamble=["G0 X1 Y1"], block_lines=50)
    got = await collect(reader)
    assert got[0] == (0, "G0 X1 Y1")
    assert got[1:] == [(n, lines[n - 1]) for n in range(777, 1001)]
    assert reader.motion == motion_flags(lines)  # flags of lines 1..776 too (resume needs them)


async def test_start_past_the_end_and_odd_line_ends(tmp_path):
    path = tmp_path / "p.gcode"
    path.write_bytes(b"G21\r\nG90\n\nG0 X1\xff Y1")  # CRLF, blank line, no final newline
    assert await collect(ProgramReader(path)) == [
        (1, "G21"), (2, "G90"), (3, ""), (4, "G0 X1\ufffd Y1")
    ]  # fmt: skip
    assert await collect(ProgramReader(path, start=9)) == []


async def test_disk_reads_happen_off_the_event_loop(tmp_path, monkeypatch):
    import plotbridge.program.reader as module

    write_program(tmp_path / "p.gcode", 300)
    threads: set[str] = set()
    original = module._read_block

    def spy(file, count):
        threads.add(threading.current_thread().name)
        return original(file, count)

    monkeypatch.setattr(module, "_read_block", spy)
    assert len(await collect(ProgramReader(tmp_path / "p.gcode", block_lines=32))) == 300
    assert threads and threading.main_thread().name not in threads


async def test_large_program_iterates_in_bounded_memory(tmp_path):
    path = tmp_path / "big.gcode"
    count = 200_000
    write_program(path, count)
    size = path.stat().st_size  # ~6 MB; as a list of str it would be ~20 MB
    reader = ProgramReader(path, block_lines=1000)
    tracemalloc.start()
    try:
        seen = 0
        async for number, _ in reader.lines():
            seen += 1
            assert number == seen
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert seen == count
    assert reader.max_held <= 2000
    # Two blocks of text plus one flag byte per line, far below the file itself.
    assert peak < count + size // 10, f"peak {peak} bytes for a {size}-byte program"


async def test_link_streams_a_file_in_order_within_128_bytes(tmp_path):
    lines = write_program(tmp_path / "p.gcode", 5000)
    board = FakeBoard(auto=False)
    async with running(board) as link:
        stop = asyncio.Event()
        drainer = asyncio.create_task(feed_slowly(board, stop, per_tick=8))
        reader = ProgramReader(tmp_path / "p.gcode", start=11, preamble=["M5"], block_lines=100)
        acked: list[int] = []
        async with contextlib.aclosing(reader.lines()) as program:
            await link.stream(program, acked.append)
        stop.set()
        await drainer
    assert acked == [0, *range(11, 5001)]
    assert board.lines[-4990:] == lines[10:] and board.max_rx <= 128
    assert reader.max_held <= 200


async def test_estop_mid_stream_ends_the_read_ahead(tmp_path):
    write_program(tmp_path / "p.gcode", 50_000)
    board = FakeBoard(auto=False)
    async with running(board) as link:
        stop = asyncio.Event()
        drainer = asyncio.create_task(feed_slowly(board, stop))
        reader = ProgramReader(tmp_path / "p.gcode", block_lines=100)
        acked: list[int] = []

        async def stream() -> None:
            async with contextlib.aclosing(reader.lines()) as program:
                await link.stream(program, acked.append)

        task = asyncio.create_task(stream())
        await asyncio.sleep(0.2)
        link.estop()
        with pytest.raises(StreamAborted) as info:
            await asyncio.wait_for(task, 2)
        stop.set()
        await drainer
    assert info.value.reason == "estop" and 0 < len(acked) < 50_000
    assert reader.held == 0 and reader.max_held <= 200
