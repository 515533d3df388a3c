"""textcheck.c: the first control byte a text file does not hold."""

from __future__ import annotations

import ctypes

from . import function


def first_control(data: bytes) -> int:
    """Where the first byte below 32 other than tab, LF, FF, CR and ^Z is in `data`; -1
    when there is none."""
    fn = function("textcheck", "first_control", [ctypes.c_char_p, ctypes.c_long],
                  ctypes.c_long)
    return fn(data, len(data))
