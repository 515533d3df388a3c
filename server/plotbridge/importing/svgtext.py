"""SVG text in a single-stroke (Hershey) font from the Hershey-Fonts package.

A pen draws each glyph stroke once, where an outline font would draw every stroke
twice. The Hershey glyphs are laid out at the text's position, size, anchor, letter
and word spacing and per-glyph rotation, on a `textPath` when there is one; the caller
applies transforms. Glyph units: y down, baseline at 9, 32 units to the em.
"""

from __future__ import annotations

import functools
import math
import re
import unicodedata
from dataclasses import dataclass

import numpy as np

from .fields import FONTS

EM_UNITS = 32.0
BASELINE = 9.0
DEFAULT_FONT = "futural"
# font-family names that the Hershey fonts stand for without substitution
HERSHEY_NAMES = re.compile(r"hershey|futura|rowman|scripts|timesr|gothic", re.I)
_NUMBER = re.compile(r"[+-]?(\d+(?:\.\d*)?|\.\d+)([eE][+-]?\d+)?")


@dataclass
class Glyph:
    left: float
    width: float
    strokes: list[np.ndarray]


@functools.lru_cache(maxsize=len(FONTS) + 1)    # and the Greek set
def _font(name: str) -> dict[str, Glyph]:
    from HersheyFonts import HersheyFonts

    font = HersheyFonts()
    font.load_default_font(name)
    table: dict[str, Glyph] = {}
    for code in range(32, 127):
        ch = chr(code)
        (g,) = font.glyphs_for_text(ch)
        strokes = [np.asarray(s, dtype=float) for s in g.strokes if len(s) > 0]
        table[ch] = Glyph(float(g.left_offset), float(g.char_width), strokes)
    return table


# Greek letters are in Hershey's Greek simplex set ("greek", the same stroke weight as
# futural) at the Latin letters of the Symbol font's layout.
GREEK_FONT = "greek"
_GREEK = dict(zip("ΑΒΓΔΕΖΗΘΙΚΛΜΝΞΟΠΡΣΤΥΦΧΨΩαβγδεζηθικλμνξοπρσςτυφχψω",
                  "ABGDEZHQIKLMNXOPRSTUFCYWabgdezhqiklmnxoprsstufcyw", strict=True))


@functools.lru_cache(maxsize=4096)
def fallback(ch: str) -> tuple[str | None, str]:
    """(font, character) that draws a character outside the Hershey fonts' ASCII table:
    a Greek letter from the Greek set, a Latin letter with marks as its base letter
    (font None: the text's font), else ("?", "?"): not drawn as itself."""
    if ch in _GREEK:
        return GREEK_FONT, _GREEK[ch]
    base = unicodedata.normalize("NFKD", ch)
    base = "".join(c for c in base if not unicodedata.combining(c))
    if len(base) == 1 and " " <= base <= "~":
        return None, base
    return "?", "?"


def glyph(font: str, ch: str) -> Glyph:
    table = _font(font)
    g = table.get(ch)
    if g is not None:
        return g
    other, sub = fallback(ch)
    if other == GREEK_FONT:
        return _font(GREEK_FONT)[sub]
    return table[sub]


def unlike(text: str) -> tuple[list[str], list[str]]:
    """The characters of `text` drawn as '?' and those drawn without their marks, each
    once, in order."""
    missing: dict[str, None] = {}
    plain: dict[str, None] = {}
    for ch in text:
        if " " <= ch <= "~" or ch in _GREEK:
            continue
        other, _ = fallback(ch)
        (missing if other == "?" else plain)[ch] = None
    return list(missing), list(plain)


def advance(font: str, text: str, size: float, letter: float, word: float) -> float:
    k = size / EM_UNITS
    return sum(glyph(font, ch).width * k + letter + (word if ch == " " else 0.0) for ch in text)


def _glyph_at(g: Glyph, x: float, y: float, k: float, degrees: float = 0.0,
              lead: float = 0.0) -> list[np.ndarray]:
    """The glyph's strokes with its origin (left edge on the baseline, moved `lead`
    along the baseline) at (x, y), turned `degrees` clockwise (y down) about (x, y)."""
    a = math.radians(degrees)
    ca, sa = math.cos(a), math.sin(a)
    out = []
    for s in g.strokes:
        lx = (s[:, 0] - g.left) * k + lead
        ly = (s[:, 1] - BASELINE) * k
        out.append(np.column_stack([x + ca * lx - sa * ly, y + sa * lx + ca * ly]))
    return out


@dataclass
class Char:
    """One addressable character of a `<text>` with what positions it: absolute x/y,
    relative dx/dy and its rotation in degrees (None where no list gives it one), and
    its run's metrics."""

    ch: str
    run: int            # index of the text run (one style) it belongs to
    size: float
    letter: float
    word: float
    anchor: str         # text-anchor, used when the character starts a text chunk
    x: float | None = None
    y: float | None = None
    dx: float | None = None
    dy: float | None = None
    rotate: float | None = None


def angles(raw: str) -> list[float]:
    """A `rotate` list: numbers (degrees) separated by white space and/or commas."""
    out = []
    for v in re.split(r"[\s,]+", raw.strip()):
        if not v:
            continue
        a = float(v) if _NUMBER.fullmatch(v) else math.nan
        if not math.isfinite(a):   # not SVG's number syntax, or too large for a float
            raise ValueError(f"rotate '{raw.strip()[:40]}': '{v[:20]}' is not a number of "
                             "degrees")
        out.append(a)
    return out


def assign(chars: list[Char], lists: dict[str, list[float]]) -> None:
    """Give the characters of one text or tspan (descendants included) the values of its
    x, y, dx, dy and rotate lists, where a descendant's own list (assigned first) has
    not: the n-th value goes to the n-th character. Characters past the end of a
    position list are left to ancestors; past the end of a rotate list they take its
    last angle."""
    for key, values in lists.items():
        if key == "rotate" and values:
            values = values + values[-1:] * (len(chars) - len(values))
        for c, v in zip(chars, values, strict=False):
            if getattr(c, key) is None:
                setattr(c, key, v)


def layout(font: str, chars: list[Char]) -> dict[int, list[np.ndarray]]:
    """Glyph strokes (user units, y down) by run, each glyph where SVG puts it: an
    absolute x or y starts a new text chunk there, dx/dy shift the glyph and all after
    it, each chunk is shifted by its anchor, and each glyph is turned by its rotation
    about its own (shifted) position; rotation does not change where the next goes."""
    x = y = 0.0
    chunks: list[tuple[str, list[tuple[Char, Glyph, float, float]]]] = []
    for c in chars:
        if c.x is not None or c.y is not None or not chunks:
            x = c.x if c.x is not None else x
            y = c.y if c.y is not None else y
            chunks.append((c.anchor, []))
        x += c.dx or 0.0
        y += c.dy or 0.0
        g = glyph(font, c.ch)
        chunks[-1][1].append((c, g, x, y))
        x += g.width * c.size / EM_UNITS + c.letter + (c.word if c.ch == " " else 0.0)
    out: dict[int, list[np.ndarray]] = {}
    for anchor, placed in chunks:
        if not placed:
            continue
        last, lg, lx, _ = placed[-1]
        end = lx + lg.width * last.size / EM_UNITS + last.letter
        width = end - placed[0][2]
        shift = {"middle": -width / 2, "end": -width}.get(anchor, 0.0)
        for c, g, px, py in placed:
            out.setdefault(c.run, []).extend(
                _glyph_at(g, px + shift, py, c.size / EM_UNITS, c.rotate or 0.0))
    return out


def along(font: str, text: str, path: np.ndarray, offset: float, size: float,
          letter: float, word: float) -> list[np.ndarray]:
    """Glyphs placed along a polyline from `offset`: each glyph's middle sits on the path,
    turned to the path's direction there; glyphs past the path's end are not drawn."""
    seg = np.diff(path, axis=0)
    lengths = np.hypot(seg[:, 0], seg[:, 1])
    cum = np.concatenate([[0.0], np.cumsum(lengths)])
    total = cum[-1]
    k = size / EM_UNITS
    out = []
    s = offset
    for ch in text:
        g = glyph(font, ch)
        w = g.width * k
        mid = s + w / 2
        if 0 <= mid <= total and total > 0:
            i = min(int(np.searchsorted(cum, mid, side="right")) - 1, len(seg) - 1)
            t = (mid - cum[i]) / lengths[i] if lengths[i] > 0 else 0.0
            px, py = path[i] + t * seg[i]
            turn = math.degrees(math.atan2(seg[i][1], seg[i][0]))
            out.extend(_glyph_at(g, px, py, k, turn, lead=-w / 2))
        s += w + letter + (word if ch == " " else 0.0)
    return out


def collapse(text: str, preserve: bool) -> str:
    """SVG 1.1 white space handling of character data."""
    if preserve:
        return text.replace("\n", " ").replace("\t", " ").replace("\r", "")
    return re.sub(r" +", " ", text.replace("\r", "").replace("\n", "").replace("\t", " "))
