"""Loads libmotion, the firmware's planner, arc and segment code built for the host
(`firmware/build/host/libmotion.so`, made by `make -C firmware`).

ctypes rather than cffi: it is in the standard library, needs no compiler or build
step at import time (the library is built by the firmware's make, like the firmware
itself), and the interface is one struct and a call per batch of thousands of lines, so
ctypes' per-call overhead does not matter. ctypes lets go of the GIL during a call, so the
estimate runs on a thread beside the import writing the program (estimate.py).
"""

from __future__ import annotations

import ctypes
import os
import subprocess
import threading
from pathlib import Path

import numpy as np

from ..native import array
from ..profiles import check_board

FIRMWARE_DIR = Path(os.environ.get("PLOTBRIDGE_FIRMWARE_DIR",
                                   Path(__file__).resolve().parents[3] / "firmware"))
DEFAULT_BOARD = "uno-cnc-shield"
DEEP_BOARD = "mega-ramps14"  # a 2560 build: the deepest planner of the profiles (63 blocks)
LIBRARY = FIRMWARE_DIR / "build" / "host" / "libmotion.so"


def library_file(board: str = DEFAULT_BOARD) -> Path:
    """Where make puts the board's build of the library (the firmware Makefile's BUILD):
    each board's build has that board's planner depth."""
    if board == DEFAULT_BOARD:
        return LIBRARY
    return FIRMWARE_DIR / "build" / board / "host" / LIBRARY.name


# Line kinds (firmware/host/motion.c OP_*).
RAPID, LINE, ARC_CW, ARC_CCW, PEN_DOWN, PEN_UP, DWELL, OTHER = range(8)


class Config(ctypes.Structure):
    _pack_ = 1    # the library packs its structs as avr-gcc does
    _fields_ = [
        ("steps_per_mm", ctypes.c_double * 2),
        ("max_rate", ctypes.c_double * 2),
        ("accel", ctypes.c_double * 2),
        ("junction_deviation", ctypes.c_double),
        ("arc_tolerance", ctypes.c_double),
        ("pen_settle_s", ctypes.c_double),
        ("corexy", ctypes.c_int),
        ("depth", ctypes.c_int),
        ("byte_s", ctypes.c_double),
        ("line_cpu_s", ctypes.c_double),
        ("rx_size", ctypes.c_int),
    ]


class MotionLibraryMissing(RuntimeError):
    pass


_libs: dict[str, ctypes.CDLL] = {}
_load_lock = threading.Lock()
# The firmware code keeps its state in globals: one program at a time per process.
run_lock = threading.Lock()


def load(board: str = DEFAULT_BOARD) -> ctypes.CDLL:
    """The board's build of the library, made first with make when it is missing."""
    with _load_lock:
        if board not in _libs:
            check_board(board, FIRMWARE_DIR)  # a profile name, never any string, reaches make
            path = library_file(board)
            if not path.exists():
                r = subprocess.run(["make", "-s", "-C", str(FIRMWARE_DIR), f"BOARD={board}",
                                    "motion"], capture_output=True, text=True)
                if r.returncode or not path.exists():
                    raise MotionLibraryMissing(
                        f"cannot build {path}: {r.stderr.strip() or r.stdout.strip()}")
            lib = ctypes.CDLL(str(path))
            lib.motion_configure.argtypes = [ctypes.POINTER(Config)]
            lib.motion_configure.restype = None
            lib.motion_plan_size.restype = ctypes.c_int
            f32 = array(np.float32, 1)
            lib.motion_feed.argtypes = [ctypes.c_int, array(np.uint8, 1), f32, f32, f32, f32,
                                        f32, array(np.uint16, 1), array(np.float64, 1)]
            lib.motion_feed.restype = None
            lib.motion_end.restype = ctypes.c_double
            lib.motion_plan.argtypes = lib.motion_feed.argtypes[:7]
            lib.motion_plan.restype = None
            lib.motion_blocks.argtypes = [ctypes.c_char_p, ctypes.c_int]
            lib.motion_blocks.restype = ctypes.c_int
            lib.motion_block_size.restype = ctypes.c_int
            _libs[board] = lib
        return _libs[board]


def planner_depth(board: str = DEFAULT_BOARD) -> int:
    """How many blocks the board's planner holds (its PLAN_SIZE - 1): the depth to
    configure the library with for that board."""
    return int(load(board).motion_plan_size())


def build_holding(board: str | None, depth: int) -> str:
    """The build whose library runs the estimate for a board of profile `board` (None:
    the default) whose planner holds `depth` blocks (0: unknown): the board's own build,
    unless the board reports a deeper planner than that build has (a Mega flashed with
    our firmware behind a server left at the default profile), then the deepest build.
    The motion code is the same in every build; only the ring's size differs."""
    own = board or DEFAULT_BOARD
    if depth > planner_depth(own):
        return DEEP_BOARD
    return own
