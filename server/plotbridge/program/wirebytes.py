"""The bytes each program line takes on the wire, for the estimate: wire.py's rules
(`Compactor.line`, `numbered`) over the estimate's arrays instead of the text, with
coordinates as integer thousandths (the program's 3 decimals) and each text's length
from its digits. Kept apart from wire.py so the server's streaming does not load numpy;
tests/unit/test_wire_bytes.py holds the two equal."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .wire import MAX_LINE_NUMBER

_POW10 = 10 ** np.arange(19, dtype=np.int64)


def _digits(a: np.ndarray) -> np.ndarray:
    """Decimal digits of each a >= 1; 0 for 0."""
    return np.searchsorted(_POW10, a, side="right")


def _text_len(m: np.ndarray) -> np.ndarray:
    """len(number(m / 1000)) for integer thousandths m: without trailing zeros or a
    leading zero, "0" for zero (a text of fewer decimals is the same text: its value in
    thousandths has the zeros)."""
    a = np.abs(m)
    whole = a // 1000
    frac = a - whole * 1000
    point = np.where(frac == 0, 0, np.where(frac % 100 == 0, 2, np.where(frac % 10 == 0, 3, 4)))
    return (m < 0) + _digits(whole) + point + (a == 0)


def _side(m: np.ndarray) -> np.ndarray:
    """Sign of float(m / 1000) - m / 1000 (the double against the exact decimal): which
    way Python's formatting rounds a tie of m thousandths. Exact: the product's rounding
    error by Dekker's splitting (x * 1000 == p + err), no fused multiply-add needed."""
    x = m / 1000.0
    p = x * 1000.0
    c = x * 134217729.0     # 2**27 + 1: splits x into 26-bit halves
    xh = c - (c - x)
    err = (xh * 1000.0 - p) + (x - xh) * 1000.0
    return np.sign((p - m) + err)


def _round(m: np.ndarray, d: int, side: np.ndarray) -> np.ndarray:
    """The digits of f"{m / 1000:.{d}f}" as an integer (d < 3): nearest, a tie as the
    double's exact value lies (`_side`), an exact tie to even."""
    r = 10 ** (3 - d)
    base = m // r
    twice = 2 * (m - base * r)
    tie = twice == r
    up = (twice > r) | (tie & ((side > 0) | ((side == 0) & (base % 2 == 1))))
    return base + up


def _steps(v: np.ndarray, spm: np.ndarray) -> np.ndarray:
    """step_of over arrays (the same float operations)."""
    t = v * spm
    return np.where(t >= 0, np.floor(t + 0.5), -np.floor(-t + 0.5))


def _on_step(m: np.ndarray, spm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For coordinates of m thousandths: len(on_step(m / 1000)) and the text's value in
    thousandths (where the board is after it)."""
    target = _steps(m / 1000.0, spm)
    side = _side(m)
    sent = m     # 3 decimals always land on the step: the value itself
    todo = np.ones(m.shape, bool)
    for d in range(3):
        q = _round(m, d, side)
        ok = todo & (_steps(q / 10.0 ** d, spm) == target)
        sent = np.where(ok, q * 10 ** (3 - d), sent)
        todo &= ~ok
    return _text_len(sent), sent


def _held(event: np.ndarray, values: np.ndarray, carry: int) -> tuple[np.ndarray, int]:
    """For each row the value of the last event row before it (`carry` before the first
    event), and the value after the last row."""
    last = np.maximum.accumulate(np.where(event, np.arange(len(event)), -1))
    after = np.where(last >= 0, values[last], carry)
    before = np.empty_like(after)
    before[0] = carry
    before[1:] = after[:-1]
    return before, int(after[-1])


@dataclass
class _Modes:
    """What the compactor remembers from line to line: the motion mode (G number, -1:
    none), the F text (tenths of mm/min, -1: none), where the original and the wire
    program are (thousandths), and the lines counted so far."""

    motion: int = -1
    feed: int = -1
    orig: tuple[int, int] = (0, 0)
    sent: tuple[int, int] = (0, 0)
    line: int = 0


class WireBytes:
    """The bytes each program line takes on the wire with its newline (and its N word
    where the board takes one), for the estimate, from arrays of the lines run after run:
    `count` gets the lines in program order, from line 1, and remembers the modal state.

    Equal to `len(numbered(n, Compactor(steps_per_mm).line(text))) + 1` for the program
    lines importing/program.py writes (coordinates of up to 3 decimals, below 8,000 mm:
    float32 keeps them to the thousandth; ties of the shorter texts' rounding as Python
    formats them). A feed is taken to the tenth as its F text is, but from float32: one
    on a tie (F1000.05, neither float exactly) may go to the other tenth than the
    double does, and its F word be counted a few bytes off (sent or not, a digit more or
    less: tests/unit/test_wire_bytes.py)."""

    def __init__(self, steps_per_mm: tuple[float, float], line_numbers: bool) -> None:
        self.spm = np.array(steps_per_mm, np.float64).reshape(2, 1)
        self.line_numbers = line_numbers
        self.modes = _Modes()

    def count(self, motion: np.ndarray, x: np.ndarray, y: np.ndarray, i: np.ndarray,
              j: np.ndarray, feed: np.ndarray, keeps: np.ndarray,
              nbytes: np.ndarray) -> np.ndarray:
        """Bytes of the next len(motion) lines. motion: the line's G number (0-3) when it
        is a motion line, above 3 when not; x, y: its end point (mm); i, j: an arc's
        centre offsets; feed (mm/min; rapids: any); for the other lines: `keeps`, true
        where the line leaves the modal state alone, and `nbytes`, its own bytes (`plain`)."""
        n = len(motion)
        if not n:
            return np.zeros(0, np.int64)
        s = self.modes
        motion = motion.astype(np.int64)
        mv = motion <= 3
        reset = ~mv & ~keeps.astype(bool)
        xy = np.rint(np.stack((x, y)).astype(np.float64) * 1000.0).astype(np.int64)
        length, sent = _on_step(xy, self.spm)
        out = length[0] + length[1] + 3      # X, Y and the newline
        mode, s.motion = _held(mv | reset, np.where(mv, motion, -1), s.motion)
        out += 2 * (mode != motion)
        fed = mv & (motion > 0)
        tenths = np.rint(feed.astype(np.float64) * 10.0).astype(np.int64)
        last_feed, s.feed = _held(fed | reset, np.where(fed, tenths, -1), s.feed)
        out += np.where(fed & (tenths != last_feed), 1 + _text_len(100 * tenths), 0)
        arc = mv & (motion >= 2)
        at = mv | reset     # where the original and the wire program are, reset to 0
        last_orig, last_sent = [], []
        for a, centre in enumerate((i, j)):
            o, after = _held(at, np.where(mv, xy[a], 0), s.orig[a])
            last_orig.append(after)
            w, after = _held(at, np.where(mv, sent[a], 0), s.sent[a])
            last_sent.append(after)
            if arc.any():   # same centre: sent start + I' = original start + I
                k = np.rint(centre.astype(np.float64) * 1000.0).astype(np.int64) + o - w
                out += np.where(arc, 1 + _text_len(k), 0)
        s.orig = (last_orig[0], last_orig[1])
        s.sent = (last_sent[0], last_sent[1])
        out = np.where(mv, out, nbytes)
        if self.line_numbers:
            ln = np.arange(s.line + 1, s.line + n + 1, dtype=np.int64)
            out += np.where(ln <= MAX_LINE_NUMBER, 1 + _digits(ln), 0)
        s.line += n
        return out
