"""GRBL 1.1 serial protocol logic: parsing, line classification, buffer accounting.

Pure functions and small state holders, no I/O. Everything here follows the
public GRBL 1.1 interface description, so it works with stock GRBL boards and
with our own firmware alike.
"""

from __future__ import annotations

import re
from collections import deque
from dataclasses import dataclass
from typing import Any

RX_BUFFER_SIZE = 128
"""Bytes of the board's serial receive buffer (GRBL's default on an ATmega328P)."""

MAX_LINE_BYTES = 256
"""Longest line accepted from the board; longer ones are garbage and dropped."""

SOFT_RESET = b"\x18"
STATUS_QUERY = b"?"
FEED_HOLD = b"!"
CYCLE_START = b"~"
REALTIME_CHARS = frozenset("?!~\x18")

ERROR_MESSAGES: dict[int, str] = {
    1: "a G-code word has no letter",
    2: "a number is missing or badly formatted",
    3: "unknown or unsupported '$' command",
    4: "a value that must be positive is negative",
    5: "homing is disabled in the settings",
    6: "the step pulse must be at least 3 microseconds",
    7: "settings in EEPROM were unreadable and have been reset to defaults",
    8: "this '$' command needs the machine to be idle",
    9: "G-code is refused while in alarm or jog state",
    10: "soft limits need homing to be enabled",
    11: "the line is too long and was not executed",
    12: "the value would exceed the highest supported step rate",
    13: "the safety door is open",
    14: "startup line or build info too long for EEPROM",
    15: "the jog target is outside the machine travel",
    16: "the jog command is malformed or contains forbidden G-code",
    17: "laser mode needs PWM output",
    20: "unsupported or invalid G-code command",
    21: "two commands of the same modal group in one line",
    22: "no feed rate has been set",
    23: "the command needs an integer value",
    24: "two commands in the line both want the axis words",
    25: "a word is repeated in the line",
    26: "the command needs axis words but the line has none",
    27: "line number (N) out of range",
    28: "the command lacks a required P or L word",
    29: "unsupported work coordinate system",
    30: "G53 needs G0 or G1 motion mode",
    31: "axis words are left over while motion is cancelled (G80)",
    32: "the arc has no axis words in the selected plane",
    33: "the motion target is invalid (impossible arc or zero-length probe)",
    34: "the radius-format arc cannot be computed",
    35: "the offset-format arc lacks its offset words in the selected plane",
    36: "the line has unused words",
    37: "tool length offset applied to an axis other than the configured one",
    38: "tool number out of range",
}

ALARM_MESSAGES: dict[int, str] = {
    1: "hard limit switch hit; position lost, home again",
    2: "motion target outside the machine travel (soft limit)",
    3: "reset while moving; position lost, home again",
    4: "probe was not in the expected state before probing",
    5: "probe did not make contact",
    6: "homing failed: reset during the homing cycle",
    7: "homing failed: safety door opened",
    8: "homing failed: pull-off did not clear the limit switch",
    9: "homing failed: limit switch not found",
    10: "emergency stop button pressed",
}


def error_message(code: int | None) -> str:
    if code is None:
        return "unknown error"
    return ERROR_MESSAGES.get(code, f"unknown error {code}")


def alarm_message(code: int | None) -> str:
    if code is None:
        return "unknown alarm"
    return ALARM_MESSAGES.get(code, f"unknown alarm {code}")


@dataclass(frozen=True)
class Status:
    """One parsed `<...>` status report. Absent fields are None."""

    state: str
    sub_state: int | None = None
    mpos: tuple[float, ...] | None = None
    wpos: tuple[float, ...] | None = None
    wco: tuple[float, ...] | None = None
    planner_free: int | None = None
    rx_free: int | None = None
    feed: float | None = None
    speed: float | None = None
    pins: str = ""
    accessories: str = ""
    line: int | None = None
    overrides: tuple[int, ...] | None = None


_STATES = {"Idle", "Run", "Hold", "Jog", "Alarm", "Door", "Check", "Home", "Sleep"}
_NUMBER = re.compile(r"^-?\d+(\.\d*)?$|^-?\.\d+$")


def _floats(text: str) -> tuple[float, ...]:
    parts = text.split(",")
    if not all(_NUMBER.match(p) for p in parts):
        raise ValueError(text)
    return tuple(float(p) for p in parts)


def _ints(text: str, count: int | None = None) -> tuple[int, ...]:
    parts = text.split(",")
    if count is not None and len(parts) != count:
        raise ValueError(text)
    return tuple(int(p) for p in parts)


def parse_status(line: str) -> Status | None:
    """Parse a GRBL 1.1 status report, or return None if `line` is not a valid one.

    A report with a malformed field is rejected as a whole rather than
    half-applied; unknown fields are ignored (later firmware may add some).
    """
    if len(line) < 3 or line[0] != "<" or line[-1] != ">":
        return None
    fields = line[1:-1].split("|")
    state, _, sub = fields[0].partition(":")
    if state not in _STATES:
        return None
    values: dict[str, Any] = {"state": state}
    try:
        if sub:
            values["sub_state"] = int(sub)
        for field in fields[1:]:
            key, sep, text = field.partition(":")
            if not sep:
                return None
            if key == "MPos":
                values["mpos"] = _floats(text)
            elif key == "WPos":
                values["wpos"] = _floats(text)
            elif key == "WCO":
                values["wco"] = _floats(text)
            elif key == "Bf":
                values["planner_free"], values["rx_free"] = _ints(text, 2)
            elif key == "FS":
                values["feed"], values["speed"] = _floats(text)[:2]
            elif key == "F":
                values["feed"] = _floats(text)[0]
            elif key == "Pn":
                values["pins"] = text
            elif key == "A":
                values["accessories"] = text
            elif key == "Ln":
                values["line"] = int(text)
            elif key == "Ov":
                values["overrides"] = _ints(text, 3)
    except ValueError:
        return None
    return Status(**values)


_BANNER = re.compile(r"^Grbl\s+(\S+)")
_SETTING = re.compile(r"^\$(\d+)=(-?\d+(?:\.\d*)?|-?\.\d+)\b")
_ERROR = re.compile(r"^error:\s*(\d+)?")
_ALARM = re.compile(r"^ALARM:\s*(\d+)?")


def classify(line: str) -> tuple[str, Any]:
    """Classify one line from the board (without its line ending).

    Returns (kind, payload):
    ok -> None; error -> code or None; alarm -> code or None; status -> Status;
    msg -> the message text; banner -> the version (e.g. "1.1h");
    setting -> (number, value); feedback -> the text inside [...]; other -> the line.
    """
    if line == "ok":
        return "ok", None
    if line.startswith("<"):
        status = parse_status(line)
        return ("status", status) if status else ("other", line)
    if match := _ERROR.match(line):
        return "error", int(match.group(1)) if match.group(1) else None
    if match := _ALARM.match(line):
        return "alarm", int(match.group(1)) if match.group(1) else None
    if line.startswith("[") and line.endswith("]"):
        inner = line[1:-1]
        if inner.startswith("MSG:"):
            return "msg", inner[4:]
        return "feedback", inner
    if match := _BANNER.match(line):
        return "banner", match.group(1)
    if match := _SETTING.match(line):
        return "setting", (int(match.group(1)), float(match.group(2)))
    return "other", line


def version_from_feedback(text: str) -> str | None:
    """The firmware version from `$I`'s `[VER:1.1h.20190825:]` feedback, else None."""
    if not text.startswith("VER:"):
        return None
    version = text[4:].split(":", 1)[0]
    return version or None


def build_of(version: str | None) -> str | None:
    """The build part of a `$I` version ("1.1h.20190825" -> "20190825"; our firmware's
    "1.1h.plotbridge" -> "plotbridge"), None when only the banner's "1.1h" is known."""
    parts = (version or "").split(".", 2)
    return parts[2] if len(parts) == 3 and parts[2] else None


def buffers_from_feedback(text: str) -> tuple[int, int] | None:
    """(planner blocks, receive-buffer bytes) from `$I`'s `[OPT:V,15,128]`, else None."""
    if not text.startswith("OPT:"):
        return None
    parts = text[4:].split(",")
    if len(parts) < 3 or not (parts[1].isdecimal() and parts[2].isdecimal()):
        return None
    return int(parts[1]), int(parts[2])


def option_letters(text: str) -> str | None:
    """The build option letters of `$I`'s `[OPT:VN,15,128]` ("VN"), else None; `N`: the
    board numbers its planner blocks and reports the executing line as `Ln:`."""
    if not text.startswith("OPT:"):
        return None
    return text[4:].split(",", 1)[0]


def line_problem(line: str) -> str | None:
    """Why `line` cannot be sent to the board as one G-code/`$` line, or None if it can.

    Realtime characters would be swallowed by the board's receive interrupt (a
    0x18 would even reset it) and break the byte accounting; non-ASCII and
    control bytes are not G-code; a line longer than the receive buffer can
    never be character-counted.
    """
    bad = sorted({c for c in line if c in REALTIME_CHARS or ord(c) < 32 or ord(c) > 126})
    if bad:
        shown = ", ".join(repr(c) for c in bad)
        return f"line contains characters that cannot be sent: {shown}"
    if cost(line) > RX_BUFFER_SIZE:
        limit = RX_BUFFER_SIZE - 1
        return f"line is {len(line)} characters; at most {limit} fit the receive buffer"
    return None


def cost(line: str) -> int:
    """Bytes a line occupies in the board's receive buffer: its text plus the newline."""
    return len(line.encode("ascii", "replace")) + 1


class CharCounter:
    """Character-counting accounting for the board's receive buffer.

    Each sent line is pushed with its cost and a tag; every `ok` or `error`
    from the board acknowledges the oldest outstanding line, in order.
    """

    def __init__(self, capacity: int = RX_BUFFER_SIZE) -> None:
        self.capacity = capacity
        self._entries: deque[tuple[int, Any]] = deque()
        self._outstanding = 0

    @property
    def outstanding(self) -> int:
        return self._outstanding

    @property
    def free(self) -> int:
        return self.capacity - self._outstanding

    def __len__(self) -> int:
        return len(self._entries)

    def fits(self, size: int) -> bool:
        return self._outstanding + size <= self.capacity

    def push(self, size: int, tag: Any = None) -> None:
        if size <= 0 or not self.fits(size):
            raise OverflowError(
                f"{size} bytes do not fit: {self._outstanding} of {self.capacity} outstanding"
            )
        self._entries.append((size, tag))
        self._outstanding += size

    def ack(self) -> Any:
        """Release the oldest line; returns its tag. LookupError when nothing is outstanding."""
        if not self._entries:
            raise LookupError("acknowledgement with nothing outstanding")
        size, tag = self._entries.popleft()
        self._outstanding -= size
        return tag

    def peek(self) -> Any:
        """The tag of the oldest outstanding line, or None."""
        return self._entries[0][1] if self._entries else None

    def tags(self) -> list[Any]:
        return [tag for _, tag in self._entries]

    def clear(self) -> list[Any]:
        """Forget everything outstanding (the board reset); returns the dropped tags."""
        tags = self.tags()
        self._entries.clear()
        self._outstanding = 0
        return tags


_NOT_TEXT = bytes(b for b in range(256) if not (32 <= b <= 126 or b == 9))


class LineSplitter:
    """Turns the board's byte stream into text lines, dropping what is not text.

    `feed()` returns (lines, problems): complete lines without endings, and
    human-readable descriptions of what was dropped (bytes that are not
    printable ASCII, such as NULs or line noise, and overlong lines), for the
    log. The printable rest of a noisy line is kept, so an `ok` behind noise
    still acknowledges its line.
    """

    def __init__(self, max_bytes: int = MAX_LINE_BYTES) -> None:
        self.max_bytes = max_bytes
        self._buf = bytearray()
        self._overlong = False

    def feed(self, data: bytes) -> tuple[list[str], list[str]]:
        lines: list[str] = []
        problems: list[str] = []
        parts = data.split(b"\n")
        for i, part in enumerate(parts):
            last = i == len(parts) - 1
            if not self._overlong:
                self._buf += part
                if len(self._buf) > self.max_bytes:
                    problems.append(f"dropped an overlong line ({len(self._buf)}+ bytes)")
                    self._buf.clear()
                    self._overlong = True
            if last:
                break
            if self._overlong:
                self._overlong = False
                continue
            raw = bytes(self._buf)
            self._buf.clear()
            text = raw.translate(None, _NOT_TEXT).decode("ascii")
            if len(text) != len(raw.replace(b"\r", b"")):
                problems.append(f"dropped bytes that are not text: {raw[:60]!r}")
            if text.strip():
                lines.append(text.strip())
        return lines, problems
