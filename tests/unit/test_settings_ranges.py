"""The server's copy of the firmware's setting ranges (plotbridge.settings_meta, shown in
the UI and checked before a write reaches the board) answers exactly as the firmware's
own `settings_set` (firmware/src/settings.c, built into the host motion library) at
every edge of every range."""

from __future__ import annotations

import ctypes

import pytest
from plotbridge import settings_meta
from plotbridge.motion.library import load

SETTINGS_BYTES = 512  # more than sizeof(settings_t): the firmware writes inside it only


@pytest.fixture(scope="module")
def firmware() -> ctypes.CDLL:
    lib = load()
    lib.settings_set.argtypes = [ctypes.c_void_p, ctypes.c_uint8, ctypes.c_float]
    lib.settings_set.restype = ctypes.c_uint8
    lib.settings_id.argtypes = [ctypes.c_uint8]
    lib.settings_id.restype = ctypes.c_uint8
    lib.settings_defaults.argtypes = [ctypes.c_void_p]
    return lib


def firmware_ids(lib: ctypes.CDLL) -> set[int]:
    count = ctypes.c_uint8.in_dll(lib, "settings_count").value
    return {lib.settings_id(i) for i in range(count)}


def accepts(lib: ctypes.CDLL, number: int, value: float, homing: bool) -> bool:
    settings = ctypes.create_string_buffer(SETTINGS_BYTES)
    lib.settings_defaults(settings)
    assert lib.settings_set(settings, 22, float(homing)) == 0
    return lib.settings_set(settings, number, value) == 0


def probes(limits: settings_meta.Range) -> list[float]:
    low, high = limits.low, limits.high
    return sorted({low - 1, low - 0.5, low, low + 0.0005, low + 0.5, low + 1, (low + high) / 2,
                   high - 1, high - 0.5, high, high + 0.5, high + 1, 0.0})  # fmt: skip


def test_the_same_settings_exist(firmware):
    assert set(settings_meta.RANGES) == firmware_ids(firmware)


@pytest.mark.parametrize("homing", [True, False])
def test_every_edge_is_answered_as_the_firmware_does(firmware, homing):
    differ = []
    for number, limits in settings_meta.RANGES.items():
        for value in probes(limits):
            if value < 0:
                continue  # refused by both, the firmware with its own error (negative)
            ours = settings_meta.check(number, value, {22: float(homing)}) is None
            if ours != accepts(firmware, number, value, homing):
                differ.append((number, value, "server accepts" if ours else "server refuses"))
    assert differ == []
