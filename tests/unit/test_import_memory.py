"""An import's memory goes back when it returns: nothing it made is left in a reference
cycle, which only the collector's rare full pass frees. An import worker runs import
after import in a capped address space; 17 MB an import stayed behind (the G-code
scan's chunks and the estimate's batches, each held by a ctypes pointer in a cycle with
its array, and the program writer held by its own bound method), so after a dozen big
uploads the next big one was refused for memory."""

from __future__ import annotations

import asyncio
import gc
import random
from pathlib import Path

import pytest
from plotbridge.importing.workers import ImportService
from plotbridge.jobs.imports import run_import

SVG = (
    '<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="150mm" viewBox="0 0 200 150">'
    '<g id="layer1"><path d="M 10 10 C 40 80 90 -20 150 60 S 180 140 20 140 Z" stroke="black" '
    'fill="none"/><circle cx="100" cy="75" r="40" stroke="red" fill="none"/></g>'
    '<text x="20" y="40" font-size="12">cycles<tspan dy="5">too</tspan></text></svg>'
)


def gcode(lines: int) -> str:
    """Random-walk strokes: more than one scan chunk and one estimate batch."""
    rng = random.Random(7)
    x = y = 50.0
    out = ["G21", "G90", "G0 X50 Y50", "M3"]
    for n in range(lines):
        x = min(max(x + rng.uniform(-1, 1), 1), 199)
        y = min(max(y + rng.uniform(-1, 1), 1), 149)
        out.append(f"G1 X{x:.4f} Y{y:.4f} F{(1500, 3000)[n % 2]} ; segment {n:07d}")
    return "\n".join([*out, "M5", ""])


def left_in_cycles(args: tuple[str, str, str], folder: str) -> list[str]:
    """In the worker: one import to warm up (modules load, caches fill), then the types
    of what a second one left for the cycle collector."""
    answers = []
    for n in range(2):
        dest = Path(folder) / f"job{n}"
        dest.mkdir()
        gc.collect()
        gc.set_debug(gc.DEBUG_SAVEALL if n else 0)
        answers.append(run_import(*args, str(dest), {}, {"settings": {}, "firmware": None})[0])
        gc.collect()
    gc.set_debug(0)
    left = sorted({type(o).__qualname__ for o in gc.garbage})
    gc.garbage.clear()
    return [*answers, *left]


@pytest.mark.parametrize("kind", ["gcode", "svg", "pattern"])
def test_an_import_leaves_nothing_for_the_collector(kind, tmp_path):
    if kind == "pattern":
        args = ("pattern", "text", "text")  # the pattern of most strokes
    else:
        source = tmp_path / f"drawing.{kind}"
        source.write_text(gcode(40_000) if kind == "gcode" else SVG)
        args = ("file", str(source), source.name)

    async def run() -> list[str]:
        service = ImportService()
        try:
            return await service.call(left_in_cycles, args, str(tmp_path))
        finally:
            service.close()

    assert asyncio.run(run()) == ["ok", "ok"]
