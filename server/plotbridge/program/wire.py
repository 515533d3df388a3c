"""The compact wire format: what the server streams to the board, not the stored program.

The stored program (docs/INTERNALS.md, "Normalized program") stays readable; on the wire
each line drops its spaces, a motion word equal to the modal one before it (`G1` after
`G1`), an unchanged `F`, trailing zeros and a leading zero (`X.5`), and every coordinate
becomes the shortest decimal that lands on the same motor step as the original
(`round(value * steps/mm)`), so the board moves exactly as it would have. Arc centre
offsets (`I`, `J`) are corrected for the start point's rounding so the centre stays put.
Plain GRBL 1.1 G-code: a stock GRBL board accepts it. Lines the compactor does not know
are sent as they are (without spaces) and make it forget the modal state.

To a board that reports the executing line (`$I` OPT letter `N`), each program line goes
with its number as an `N` word (`N120X5Y7`), which comes back as the status report's
`Ln:`; lines numbered 0 (a resume's preamble) and `$` commands go without.

native/wirebytes.c counts, for the estimate, the bytes each program line takes on the
wire from the estimate's arrays: these rules over arrays, in C (keep the two in step;
tests/unit/test_wire_bytes.py holds them equal line for line).
"""

from __future__ import annotations

import math
from collections.abc import AsyncIterable, AsyncIterator, Iterable, Iterator

MOTION = ("G0", "G1", "G2", "G3")
MAX_LINE_NUMBER = 10_000_000  # GRBL's largest N (error:27 above it)
KEEPS_MODES = ("M3", "M5", "G21", "G90")   # lines that leave the motion mode and F alone


def plain(text: str) -> tuple[int, bool]:
    """A program line that is no motion (`M3`, `G4 P0.500`): its bytes on the wire with
    the newline (no N word), and whether it leaves the modal state alone."""
    head = text.split(maxsplit=1)[0] if text else ""
    return len(text) - text.count(" ") + 1, head in KEEPS_MODES or head in MOTION


def number(v: float, decimals: int = 3) -> str:
    """`v` with at most `decimals` decimals, no trailing zeros, no leading zero."""
    s = f"{v:.{decimals}f}"
    if "." in s:
        s = s.rstrip("0").rstrip(".")
    if s in ("-0", ""):
        return "0"
    if s.startswith("0."):
        return s[1:]
    if s.startswith("-0."):
        return "-" + s[2:]
    return s


def step_of(v: float, steps_per_mm: float) -> int:
    """The motor step the firmware rounds `v` mm to (lroundf: halves away from zero)."""
    t = v * steps_per_mm
    return math.floor(t + 0.5) if t >= 0 else -math.floor(-t + 0.5)


def on_step(v: float, steps_per_mm: float) -> str:
    """The shortest text of at most 3 decimals that lands on the same step as `v`."""
    n = step_of(v, steps_per_mm)
    for d in range(4):
        s = number(v, d)
        if step_of(float(s), steps_per_mm) == n:
            return s
    return number(v, 4)


class Compactor:
    """Turns normalized program lines into wire lines, one for one."""

    def __init__(self, steps_per_mm: tuple[float, float] = (80.0, 80.0)) -> None:
        self.spm = steps_per_mm
        self.reset()

    def reset(self) -> None:
        self.motion: str | None = None
        self.feed: str | None = None
        self.orig = (0.0, 0.0)    # where the original program is
        self.sent = (0.0, 0.0)    # where the wire program is (the same steps)

    def line(self, text: str) -> str:
        words = text.split()
        if not words:
            return ""
        head = words[0]
        if head not in MOTION:
            if head not in KEEPS_MODES:
                self.reset()
            return "".join(words)
        vals: dict[str, float] = {}
        for w in words[1:]:
            try:
                vals[w[0]] = float(w[1:])
            except (ValueError, IndexError):
                self.reset()
                return "".join(words)
        out = [] if head == self.motion else [head]
        self.motion = head
        x, y = vals.get("X", self.orig[0]), vals.get("Y", self.orig[1])
        xs, ys = on_step(x, self.spm[0]), on_step(y, self.spm[1])
        if "X" in vals:
            out.append("X" + xs)
        if "Y" in vals:
            out.append("Y" + ys)
        if "I" in vals or "J" in vals:
            # same centre: sent start + I' = original start + I
            i = vals.get("I", 0.0) + self.orig[0] - self.sent[0]
            j = vals.get("J", 0.0) + self.orig[1] - self.sent[1]
            out += ["I" + number(i, 4), "J" + number(j, 4)]
        for letter, v in vals.items():
            if letter not in "XYIJF":
                out.append(letter + number(v, 4))
        if "F" in vals:
            f = number(vals["F"], 1)
            if f != self.feed:
                out.append("F" + f)
                self.feed = f
        self.orig = (x, y)
        self.sent = (float(xs), float(ys))
        return "".join(out) or head


def numbered(n: int, text: str) -> str:
    """`text` with its program line number `n` as an `N` word where the board takes one."""
    if not text or text.startswith("$") or not 0 < n <= MAX_LINE_NUMBER:
        return text
    return f"N{n}{text}"


def compact(lines: Iterable[tuple[int, str]],
            steps_per_mm: tuple[float, float] = (80.0, 80.0)) -> Iterator[tuple[int, str]]:
    c = Compactor(steps_per_mm)
    for n, text in lines:
        yield n, c.line(text)


async def compact_async(lines: AsyncIterable[tuple[int, str]],
                        settings: dict[int, float] | None = None,
                        line_numbers: bool = False) -> AsyncIterator[tuple[int, str]]:
    """The streaming hook: (line number, text) pairs in, the same numbers with wire text
    out; `settings` is the board's $$ (steps/mm from $100, $101); `line_numbers`: the
    board reports `Ln:`, so each line carries its number."""
    s = settings or {}
    c = Compactor((float(s.get(100, 80.0)), float(s.get(101, 80.0))))
    async for n, text in lines:
        wire = c.line(text)
        yield n, numbered(n, wire) if line_numbers else wire
