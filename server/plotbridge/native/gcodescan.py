"""gcodescan.c: the G-code importer's fast path, reading the common lines of a chunk."""

from __future__ import annotations

import ctypes

import numpy as np

from . import library

_f64 = np.ctypeslib.ndpointer(np.float64, flags="C_CONTIGUOUS")
_u8 = np.ctypeslib.ndpointer(np.uint8, flags="C_CONTIGUOUS")
OTHER, RAPID, LINE = 0, 1, 2


def _scanner():
    lib = library("gcodescan")
    fn = lib.gcode_scan
    if fn.restype is not ctypes.c_long:
        fn.argtypes = [ctypes.c_char_p, ctypes.c_long, ctypes.c_long, ctypes.c_long, _u8,
                       _f64, _f64, _f64]
        fn.restype = ctypes.c_long
    return fn


def scan(text: str, max_line: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(kind, x, y, f) of each line of `text` (which ends with a newline): kind OTHER,
    RAPID (G0) or LINE (G1) for a common line of at most `max_line` characters, whose
    X, Y and F (NaN when absent) the other arrays hold."""
    data = text.encode("utf-8", "surrogateescape")
    n = data.count(b"\n")
    kind = np.empty(n, np.uint8)
    x, y, f = np.empty(n), np.empty(n), np.empty(n)
    got = _scanner()(data, len(data), n, max_line, kind, x, y, f)
    assert got == n
    return kind, x, y, f
