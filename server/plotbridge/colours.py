"""Colours in words: what a person calls a `#rrggbb` (a layer split by stroke colour is
named by its code), so no text shown to a user names a hex code (docs/INTERNALS.md,
"Pen changes between layers")."""

from __future__ import annotations

import re

CODE = re.compile(r"^#(?:[0-9a-fA-F]{3}){1,2}$")

# (word, (r, g, b)): the colours pens come in, with the codes drawings use for them
NAMES: tuple[tuple[str, tuple[int, int, int]], ...] = (
    ("black", (0, 0, 0)), ("dark grey", (80, 80, 80)), ("grey", (128, 128, 128)),
    ("light grey", (192, 192, 192)), ("white", (255, 255, 255)),
    ("red", (220, 20, 20)), ("dark red", (128, 0, 0)), ("pink", (255, 150, 190)),
    ("magenta", (230, 0, 200)), ("orange", (255, 140, 0)), ("brown", (140, 80, 20)),
    ("yellow", (250, 230, 0)), ("olive", (128, 128, 0)), ("green", (0, 160, 0)),
    ("dark green", (0, 90, 0)), ("light green", (130, 230, 110)), ("teal", (0, 128, 128)),
    ("cyan", (0, 220, 230)), ("light blue", (120, 180, 250)), ("blue", (20, 60, 230)),
    ("blue", (30, 110, 190)),
    ("navy", (0, 0, 128)), ("purple", (120, 40, 170)), ("violet", (180, 120, 230)),
)  # fmt: skip


def is_code(text: str | None) -> bool:
    """Whether `text` is a colour code (#rgb or #rrggbb)."""
    return bool(text) and CODE.match(text.strip()) is not None  # type: ignore[union-attr]


def word(code: str) -> str:
    """The nearest colour word for `#rgb`/`#rrggbb` (by the "redmean" weighted distance,
    closer to what the eye sees than plain RGB); "" for what is no code."""
    if not is_code(code):
        return ""
    digits = code.strip()[1:]
    if len(digits) == 3:
        digits = "".join(c * 2 for c in digits)
    r, g, b = (int(digits[i:i + 2], 16) for i in (0, 2, 4))

    def distance(rgb: tuple[int, int, int]) -> float:
        mean = (r + rgb[0]) / 2
        dr, dg, db = r - rgb[0], g - rgb[1], b - rgb[2]
        return (2 + mean / 256) * dr * dr + 4 * dg * dg + (2 + (255 - mean) / 256) * db * db

    return min(NAMES, key=lambda item: distance(item[1]))[0]


def label(name: str | None, colour: str | None = None) -> str:
    """A layer's name as a person reads it: its name, unless that is a colour code (then
    the colour's word); "" when it has neither."""
    if name and not is_code(name):
        return name
    return word(name or "") or word(colour or "")
