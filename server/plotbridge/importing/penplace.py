"""Pen-downs of a G-code source as the drawing has them (issue 32).

A pen-down with no move before the next pen-up (a generator's pen test at its origin,
a registration dot) is not a stroke: it is dropped, with a warning, and does not count
in the bounds, so placement does not fit the drawing around it. A pen-down that is
drawn goes down where the source's pen is: when nothing has moved yet (the source's
origin), a pen-up travel there comes first, so a placed drawing's first stroke starts
where placement put it, not at the machine's origin.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

import numpy as np

from ..native.gcodescan import LINE, OTHER, PEN_DOWN, PEN_UP, RAPID
from .models import ErrorLog
from .ops import ARC, DWELL, MOVE, MOVES, PATH, PEN

DOT = "pen-down with no move before the pen-up dropped: it draws nothing but a dot"


class PenPlacer:
    def __init__(self, errors: ErrorLog | None) -> None:
        self.errors = errors
        self.x = self.y = 0.0          # the source's pen position
        self.moved = False             # a move went to the writer (it is where the pen is)
        self.down = False
        self.pending: int | None = None   # a pen-down held back until something moves (its line)
        self.pending_held = False
        self.dwells: list[tuple] = []     # dwells after the held pen-down: its settle time

    def _dot(self, line: int | None, times: int = 1) -> None:
        """A held pen-down dropped (with its dwells)."""
        self.pending, self.pending_held = None, False
        self.dwells = []
        if self.errors is not None and times:
            self.errors.warn(line, DOT, times)

    def _release(self) -> Iterator[tuple]:
        line = self.pending
        if not self.moved:
            self.moved = True
            yield (MOVE, line, self.x, self.y, None)
        self.pending = None
        self.pending_held = False
        self.down = True
        yield (PEN, line, True)
        yield from self.dwells
        self.dwells = []

    def ops(self, ops: Iterable[tuple]) -> Iterator[tuple]:
        for op in ops:
            kind = op[0]
            if kind == PEN:
                if op[2]:
                    if not self.down and not self.pending_held:
                        self.pending, self.pending_held = op[1], True
                elif self.pending_held:
                    self._dot(self.pending)
                elif self.down:
                    self.down = False
                    yield op
            elif kind == MOVE or kind == ARC:
                if self.pending_held and (kind == ARC or (op[2], op[3]) != (self.x, self.y)):
                    yield from self._release()
                self.moved = True
                self.x, self.y = op[2], op[3]
                yield op
            elif kind == MOVES:
                yield from self._moves(op)
            elif kind == PATH:
                yield from self._path(op)
            elif kind == DWELL and self.pending_held:
                self.dwells.append(op)
            else:
                yield op

    def _moving(self, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        """Which of consecutive points differ from the one before (the pen's first)."""
        px = np.empty(len(xs))
        py = np.empty(len(ys))
        px[0], py[0] = self.x, self.y
        px[1:], py[1:] = xs[:-1], ys[:-1]
        return (xs != px) | (ys != py)

    def _moves(self, op: tuple) -> Iterator[tuple]:
        _, first, xs, ys, feeds = op
        if not len(xs):
            return
        if self.pending_held:
            moving = self._moving(xs, ys)
            if moving.any():
                k = int(np.argmax(moving))
                if k:
                    self.moved = True
                    yield (MOVES, first, xs[:k], ys[:k], feeds[:k])
                    self.x, self.y = float(xs[k - 1]), float(ys[k - 1])
                yield from self._release()
                op = (MOVES, None if first is None else first + k, xs[k:], ys[k:], feeds[k:])
        self.moved = True
        self.x, self.y = float(xs[-1]), float(ys[-1])
        yield op

    def _path(self, op: tuple) -> Iterator[tuple]:
        _, first, kinds, xs, ys, feeds = op
        n = len(kinds)
        if not n:
            return
        mv = np.flatnonzero((kinds == RAPID) | (kinds == LINE))
        pens = np.flatnonzero(kinds >= PEN_DOWN)
        if self.pending_held or (not self.moved and len(pens)):
            yield from self._path_head(op, mv, pens)
            return
        if not len(pens):
            self._after(xs, ys, mv)
            yield op
            return
        moving = mv[self._moving(xs[mv], ys[mv])] if len(mv) else mv
        nxt = np.append(pens[1:], n)
        count = np.searchsorted(moving, nxt) - np.searchsorted(moving, pens)
        downs = kinds[pens] == PEN_DOWN
        still = downs & (count == 0)
        if still.any():
            kinds = kinds.copy()
            dots = pens[still & (nxt < n)]
            kinds[dots] = OTHER
            kinds[nxt[still & (nxt < n)]] = OTHER
            if len(dots):
                self._dot(first + int(dots[0]), len(dots))
            if still[-1] and nxt[-1] == n:         # down at the end: held for what follows
                kinds[pens[-1]] = OTHER
                self.pending, self.pending_held = first + int(pens[-1]), True
        effective = kinds[pens]
        last = effective[effective != OTHER]
        if len(last):
            self.down = bool(last[-1] == PEN_DOWN)
        self._after(xs, ys, mv)
        yield (PATH, first, kinds, xs, ys, feeds)

    def _after(self, xs: np.ndarray, ys: np.ndarray, mv: np.ndarray) -> None:
        if len(mv):
            self.moved = True
            self.x, self.y = float(xs[mv[-1]]), float(ys[mv[-1]])

    def _path_head(self, op: tuple, mv: np.ndarray, pens: np.ndarray) -> Iterator[tuple]:
        """A PATH op entered with a pen-down held, or before anything moved: split where
        the held pen-down is resolved (or the first pen-down is), the rest as usual."""
        _, first, kinds, xs, ys, feeds = op

        def part(a: int, b: int) -> tuple:
            return (PATH, first + a, kinds[a:b], xs[a:b], ys[a:b], feeds[a:b])

        n = len(kinds)
        moving = mv[self._moving(xs[mv], ys[mv])] if len(mv) else mv
        if self.pending_held:
            up = int(pens[0]) if len(pens) else n     # the first pen line is an up
            go = int(moving[0]) if len(moving) else n
            if go < up:                         # it moves: the pen goes down there
                if go:
                    yield from self._path(part(0, go))
                yield from self._release()
                yield from self._path(part(go, n))
                return
            if up == n:                         # nothing moves, no pen-up: still held
                self._after(xs, ys, mv)
                yield op
                return
            self._dot(self.pending)             # a pen-up: a dot, dropped
            kinds = kinds.copy()
            kinds[up] = OTHER
            if up:
                yield from self._path(part(0, up))
            yield from self._path((PATH, first + up, kinds[up:], xs[up:], ys[up:], feeds[up:]))
            return
        # nothing moved yet and a pen line here: the first pen-down held like a PEN op
        p = int(pens[0])
        first_mv = int(mv[0]) if len(mv) else n
        if first_mv < p:                        # a move comes first: the writer is placed
            yield from self._path(part(0, first_mv + 1))
            yield from self._path(part(first_mv + 1, n))
            return
        if kinds[p] == PEN_UP:                  # an up while up: as it is
            yield part(0, p + 1)
        else:
            if p:
                yield part(0, p)
            self.pending, self.pending_held = first + p, True
        if p + 1 < n:
            yield from self._path(part(p + 1, n))


def placed_pens(ops: Iterable[tuple], errors: ErrorLog | None) -> Iterator[tuple]:
    """The ops with pen-downs as the drawing has them (module doc); warnings to `errors`
    (None: none, for a second pass over the same source)."""
    return PenPlacer(errors).ops(ops)
