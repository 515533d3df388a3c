"""Names, units and descriptions of the board's `$` settings, for the UI.

GRBL's standard numbers plus our plotter extras at 60+ (docs/INTERNALS.md).
Settings a board reports that are not listed here are shown by number only.
"""

from __future__ import annotations

from typing import NamedTuple


class SettingInfo(NamedTuple):
    name: str
    unit: str
    description: str


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

