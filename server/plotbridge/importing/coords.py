"""The SD-card coordinates list: one number per line, x then y, millimetres; the pen
is up for the first point and down for the rest."""

from __future__ import annotations

import re
from collections.abc import Iterable

from .models import ErrorLog
from .ops import Stroke

_NUMBER = re.compile(r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?")


def read_coords(lines: Iterable[tuple[int, str]], errors: ErrorLog) -> list[Stroke]:
    values: list[float] = []
    last = 0
    for n, text in lines:
        t = text.strip()
        if not t:
            continue
        if _NUMBER.fullmatch(t) is None:
            errors.add(n, f"expected one number, found '{t[:40]}'")
            continue
        values.append(float(t))
        last = n
    if not errors and len(values) % 2:
        errors.add(last, "odd count of numbers: the last x has no y")
    if not errors and len(values) < 4:
        errors.add(None, "a coordinates list needs at least two points")
    return [list(zip(values[0::2], values[1::2], strict=False))]
