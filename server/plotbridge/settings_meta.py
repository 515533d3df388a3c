"""Names, units, descriptions and allowed values of the board's `$` settings.

GRBL's standard numbers plus our plotter extras at 60+ (docs/INTERNALS.md).
Settings a board reports that are not listed here are shown by number only.
The ranges are our firmware's own checks (`settings_set` in firmware/src/settings.c),
so the server can refuse a value with its range before the board answers a bare
`error:3`; `check` applies them.
"""

from __future__ import annotations

from typing import Literal, NamedTuple

Kind = Literal["number", "integer", "bool", "mask", "enum", "fixed"]
FLOAT_MAX = 1.0e6  # the firmware refuses larger floats (step counts would overflow)


class SettingInfo(NamedTuple):
    name: str
    unit: str
    description: str


def _num(value: float) -> str:
    return f"{value:.0f}" if value == int(value) else f"{value:g}"  # 1000000, not 1e+06


class Range(NamedTuple):
    """What the firmware accepts: `low`..`high` (`low` itself excluded when `above`)."""

    kind: Kind
    low: float
    high: float
    above: bool = False  # the value must be more than `low` (a zero would divide by zero)

    def describe(self) -> str:
        if self.kind == "fixed":
            return f"fixed at {self.low:g}"
        if self.kind == "bool":
            return "0 or 1"
        low = f"more than {_num(self.low)}" if self.above else _num(self.low)
        sort = " (a whole number)" if self.kind in ("integer", "mask", "enum") else ""
        return f"{low} to {_num(self.high)}{sort}"

    def public(self) -> dict[str, object]:
        return {"kind": self.kind, "min": self.low, "max": self.high,
                "min_exclusive": self.above, "text": self.describe()}  # fmt: skip


SETTINGS: dict[int, SettingInfo] = {
    0: SettingInfo("Step pulse", "µs", "Length of each step pulse sent to the drivers."),
    1: SettingInfo(
        "Step idle delay", "ms",
        "How long the motors stay powered after motion stops; 255 keeps them enabled.",
    ),
    2: SettingInfo("Step invert mask", "mask", "Inverts step pulses (bit 0 X, bit 1 Y)."),
    3: SettingInfo("Direction invert mask", "mask", "Reverses an axis (bit 0 X, bit 1 Y)."),
    4: SettingInfo("Invert enable pin", "bool", "Inverts the stepper enable signal."),
    5: SettingInfo("Limit pins invert", "mask", "Inverts the limit switch inputs."),
    6: SettingInfo("Probe pin invert", "bool", "Inverts the probe input."),
    10: SettingInfo(
        "Status report options", "mask",
        "What status reports contain (bit 0 machine position, bit 1 buffer state).",
    ),
    11: SettingInfo(
        "Junction deviation", "mm",
        "How fast corners are taken: larger is faster but rougher.",
    ),
    12: SettingInfo("Arc tolerance", "mm", "Largest deviation of arc segments from the true arc."),
    13: SettingInfo("Report in inches", "bool", "Reports positions in inches instead of mm."),
    20: SettingInfo("Soft limits", "bool", "Refuses motion outside the work area (needs homing)."),
    21: SettingInfo("Hard limits", "bool", "Stops everything when a limit switch closes."),
    22: SettingInfo("Homing cycle", "bool", "Enables homing with $H; the board starts locked."),
    23: SettingInfo("Homing direction invert", "mask", "Axes that home toward their minimum."),
    24: SettingInfo("Homing locate feed", "mm/min", "Slow feed for the precise switch search."),
    25: SettingInfo("Homing seek rate", "mm/min", "Fast feed for the first switch search."),
    26: SettingInfo("Homing debounce", "ms", "Delay to let a limit switch settle."),
    27: SettingInfo("Homing pull-off", "mm", "Distance to back off a switch after homing."),
    30: SettingInfo("Maximum spindle speed", "RPM", "Spindle speed at full PWM output."),
    31: SettingInfo("Minimum spindle speed", "RPM", "Spindle speed at the lowest PWM output."),
    32: SettingInfo("Laser mode", "bool", "Moves continuously through spindle changes."),
    60: SettingInfo("Pen-up servo pulse", "µs", "Servo pulse width that lifts the pen."),
    61: SettingInfo("Pen-down servo pulse", "µs", "Servo pulse width that lowers the pen."),
    62: SettingInfo("Pen settle time", "ms", "Pause after each pen move before motion resumes."),
    63: SettingInfo("Kinematics", "enum", "0 cartesian, 1 CoreXY."),
    64: SettingInfo("Pen lowering time", "ms",
                    "Servo time from pen-up to pen-down (0: at once; slower leaves no dot)."),
    65: SettingInfo("Pen raising time", "ms", "Servo time from pen-down to pen-up (0: at once)."),
    100: SettingInfo("X steps per mm", "steps/mm", "Motor steps for one mm of X travel."),
    101: SettingInfo("Y steps per mm", "steps/mm", "Motor steps for one mm of Y travel."),
    102: SettingInfo("Z steps per mm", "steps/mm", "Motor steps for one mm of Z travel."),
    110: SettingInfo("X maximum rate", "mm/min", "Fastest X speed, also used for travel moves."),
    111: SettingInfo("Y maximum rate", "mm/min", "Fastest Y speed, also used for travel moves."),
    112: SettingInfo("Z maximum rate", "mm/min", "Fastest Z speed."),
    120: SettingInfo("X acceleration", "mm/s²", "How fast X speeds up and slows down."),
    121: SettingInfo("Y acceleration", "mm/s²", "How fast Y speeds up and slows down."),
    122: SettingInfo("Z acceleration", "mm/s²", "How fast Z speeds up and slows down."),
    130: SettingInfo("X maximum travel", "mm", "Width of the work area."),
    131: SettingInfo("Y maximum travel", "mm", "Depth of the work area."),
    132: SettingInfo("Z maximum travel", "mm", "Z travel."),
}


def _ranges() -> dict[int, Range]:
    """firmware/src/settings.c's limits; tests/unit/test_settings_ranges.py holds the two
    equal by asking the firmware's own code at every edge."""
    out: dict[int, Range] = {}
    for n in (11, 12, 24, 25, 110, 111, 120, 121, 130, 131):
        out[n] = Range("number", 0, FLOAT_MAX, above=True)
    out[27] = Range("number", 0, FLOAT_MAX)  # a zero pull-off is allowed
    out[100] = out[101] = Range("number", 0, 2000, above=True)
    out[0] = Range("integer", 3, 12)  # the pulse must fit well inside a 40 kHz period
    out[1] = Range("integer", 0, 255)
    for n in (2, 3, 5, 10, 23):
        out[n] = Range("mask", 0, 3)
    for n in (4, 13, 20, 21, 22):
        out[n] = Range("bool", 0, 1)
    out[63] = Range("enum", 0, 1)
    out[60] = out[61] = Range("integer", 500, 2500)  # servo pulse widths
    out[26] = out[62] = out[64] = out[65] = Range("integer", 0, 10000)
    for n, fixed in ((6, 0), (31, 0), (32, 0), (30, 1000), (102, 100), (122, 100),
                     (112, 1000), (132, 10)):  # fmt: skip
        out[n] = Range("fixed", fixed, fixed)
    return out


RANGES: dict[int, Range] = _ranges()

Group = Literal["motion", "pen", "switches", "area", "board", "other"]
GROUPS: dict[Group, tuple[int, ...]] = {
    # as GRBL users read them: each kind with its axes together (steps, rate, acceleration)
    "motion": (100, 101, 110, 111, 120, 121, 11, 12, 63),
    "pen": (60, 61, 62, 64, 65),
    # homing on, then its direction, speeds, debounce and pull-off; then the limits
    "switches": (22, 23, 25, 24, 26, 27, 21, 20, 5),
    "area": (130, 131),
    "board": (0, 1, 2, 3, 4, 10, 13),
    "other": (6, 30, 31, 32, 102, 112, 122, 132),
}
"""What a plotter user means by each setting, in the order shown; "other" (spindle, probe,
laser, Z) does not apply to a pen plotter: the UI hides it unless asked."""
_GROUP_OF = {number: group for group, numbers in GROUPS.items() for number in numbers}
_ORDER = {number: (g, i) for g, numbers in enumerate(GROUPS.values())
          for i, number in enumerate(numbers)}  # fmt: skip


def group(number: int) -> Group:
    return _GROUP_OF.get(number, "other")


def shown_order(number: int) -> tuple[int, int, int]:
    """Where `number` comes in the settings list: by group, then as GROUPS orders it; a
    number nobody knows comes last, by number."""
    g, i = _ORDER.get(number, (len(GROUPS), 0))
    return g, i, number
MASK_BITS = ("X", "Y")  # bit 0, bit 1 of every mask setting


def check(number: int, value: float, settings: dict[int, float]) -> str | None:
    """Why the firmware would refuse `$number=value` (the board's other `settings`,
    with the values written in the same batch), or None when it accepts it."""
    limits = RANGES.get(number)
    if limits is None:
        return None
    where = f"${number}={value:g}"
    if limits.kind == "fixed":
        if abs(value - limits.low) < 0.001:
            return None
        return f"{where}: ${number} is {limits.describe()} on this firmware"
    if value != value:
        return f"{where}: not a number"
    if limits.kind != "number":
        value = float(int(value))  # as GRBL: a whole-number setting drops the fraction
    below = value <= limits.low if limits.above else value < limits.low
    if below or value > limits.high:
        return f"{where} is out of range: ${number} takes {limits.describe()}"
    if number == 20 and value and not settings.get(22):
        return f"{where}: soft limits need homing; set $22=1 first (or in the same save)"
    return None
