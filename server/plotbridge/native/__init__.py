"""The server's own C helpers (C files here, built by `make native`, part of `make
setup`, into build/), loaded with ctypes: standard library, no build step at import
time, and each helper is called once per large batch, so the per-call cost of ctypes
does not matter. A helper missing at first use is built then."""

from __future__ import annotations

import ctypes
import functools
import subprocess
import threading
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[2]
_lock = threading.Lock()
_loaded: dict[str, ctypes.CDLL] = {}


class NativeMissing(RuntimeError):
    pass


def library(name: str) -> ctypes.CDLL:
    """build/lib<name>.so, made first when missing."""
    with _lock:
        lib = _loaded.get(name)
        if lib is None:
            path = HERE / "build" / f"lib{name}.so"
            if not path.exists():
                r = subprocess.run(["make", "-s", "-C", str(REPO), "native"],
                                   capture_output=True, text=True)
                if r.returncode or not path.exists():
                    raise NativeMissing(f"cannot build {path}: "
                                        f"{r.stderr.strip() or r.stdout.strip()}")
            lib = _loaded[name] = ctypes.CDLL(str(path))
        return lib


@functools.cache
def array(dtype: Any, ndim: int | None = None) -> Any:
    """An argtype for a C-contiguous numpy array of `dtype` (and `ndim` dimensions), passed
    as its address. numpy's ndpointer passes `a.ctypes`, whose pointer forms a reference
    cycle with the array: each call's arrays lived on until the collector's next full
    pass (an import worker grew by tens of MB an import)."""
    want = np.dtype(dtype)

    class Array:
        @staticmethod
        def from_param(a: Any) -> ctypes.c_void_p:
            if not (isinstance(a, np.ndarray) and a.dtype == want and a.flags.c_contiguous
                    and (ndim is None or a.ndim == ndim)):
                raise TypeError(f"expected a C-contiguous {want} array, got {type(a).__name__}")
            return ctypes.c_void_p(a.ctypes.data)

    return Array


def function(name: str, symbol: str, argtypes: list[Any], restype: Any) -> Any:
    """`symbol` of build/lib<name>.so with its C signature declared (on first use)."""
    fn = getattr(library(name), symbol)  # ctypes hands out the same object each time
    if fn.argtypes is None:
        fn.argtypes, fn.restype = argtypes, restype
    return fn
