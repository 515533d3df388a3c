"""The pen library (docs/INTERNALS.md, "Pen library"): pens with their servo positions,
speed and odometer, applied to each job layer as it plots.

Entry point: `PenLibrary`; `PenFeed` is the streaming side the runner uses.
"""

from plotbridge.pens.feed import PenFeed
from plotbridge.pens.library import PenLibrary
from plotbridge.pens.model import LayerPensBody, Pen, PenPatch, PenSpec, TryBody
from plotbridge.pens.servo import servo_lines

__all__ = ["LayerPensBody", "Pen", "PenFeed", "PenLibrary", "PenPatch", "PenSpec", "TryBody",
           "servo_lines"]  # fmt: skip
