"""SVG styling: lengths, colours, the CSS cascade (simple selectors) and inheritance."""

from __future__ import annotations

import functools
import re
from xml.etree.ElementTree import Element

import svgelements as se

from . import pathdata

SVG_NS = "{http://www.w3.org/2000/svg}"
INHERITED = ("stroke", "stroke-width", "stroke-opacity", "fill", "fill-opacity", "fill-rule",
             "clip-rule", "visibility", "color", "font-family", "font-size", "text-anchor",
             "letter-spacing", "word-spacing", "marker-start", "marker-mid", "marker-end")
OWN = ("display", "opacity", "clip-path", "mask", "overflow", "transform", "marker")
FONT_SIZES = {"xx-small": 9.0, "x-small": 10.0, "small": 13.0, "medium": 16.0, "large": 18.0,
              "x-large": 24.0, "xx-large": 32.0, "xxx-large": 48.0}
PROPERTIES = frozenset(INHERITED + OWN)
ROOT_STYLE = {"stroke": "none", "stroke-width": "1", "stroke-opacity": "1", "fill": "black",
              "fill-opacity": "1", "fill-rule": "nonzero", "clip-rule": "nonzero",
              "visibility": "visible", "color": "black", "font-family": "sans-serif",
              "font-size": "16", "text-anchor": "start", "letter-spacing": "normal",
              "word-spacing": "normal"}
UNITS = {"": 1.0, "px": 1.0, "mm": 96 / 25.4, "cm": 96 / 2.54, "in": 96.0, "pt": 96 / 72,
         "pc": 16.0, "q": 96 / 25.4 / 4}
# No two parts of these can take the same characters: linear on any input.
_LENGTH = re.compile(r"[ \t\n\f\r]*([-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?)"
                     r"([a-zA-Z%]*)[ \t\n\f\r]*")
_URL = re.compile(r"url\([ \t\n\f\r]*['\"]?#([^'\")\s]+)['\"]?[ \t\n\f\r]*\)")
_IMPORTANT = re.compile(r"![ \t\n\f\r]*important[ \t\n\f\r]*$", re.I)
MAX_VALUE = 4096      # a longer property value is not read (no colour or length is that long)


def local(tag: object) -> str | None:
    """The SVG element name of a tag, None for other namespaces and comments."""
    if not isinstance(tag, str):
        return None
    if tag.startswith(SVG_NS):
        return tag[len(SVG_NS):]
    return None if tag.startswith("{") else tag


def length(value: str | None, ref: float = 0.0, font: float = 16.0,
           default: float = 0.0) -> float:
    """A length in user units (px); % of `ref`; ValueError for what is not a length."""
    if value is None or not value.strip():
        return default
    m = _LENGTH.fullmatch(value)
    if m is None:
        raise ValueError(f"'{value[:40]}' is not a length")
    n, unit = float(m.group(1)), m.group(2).lower()
    if unit == "%":
        return n * ref / 100
    if unit == "em":
        return n * font
    if unit == "ex":
        return n * font / 2
    if unit not in UNITS:
        raise ValueError(f"unknown unit '{unit}' in '{value[:40]}'")
    return n * UNITS[unit]


def numbers(value: str | None) -> list[float]:
    """The numbers of a list (viewBox), [] when it is not one."""
    vals, error = pathdata.numbers(value)
    return [] if error else vals


def url_id(value: str | None) -> str | None:
    if not value:
        return None
    m = _URL.search(value)
    return m.group(1) if m else None


def href(elem: Element) -> str | None:
    v = elem.get("href") or elem.get("{http://www.w3.org/1999/xlink}href")
    return v[1:] if v and v.startswith("#") else None


@functools.lru_cache(maxsize=1024)
def _colour(value: str) -> tuple[str, float] | None:
    v = value.strip().lower()
    if v in ("none", "transparent", "") or len(v) > 100:
        return None
    if v.startswith("url("):      # a gradient or pattern paints: visible, colour unknown
        return "#000000", 1.0
    c = se.Color(v)
    if c.value is None:
        return None
    return c.hex[:7], (c.alpha / 255.0 if c.alpha is not None else 1.0)


def paint(style: dict[str, str], key: str) -> tuple[str, float] | None:
    """(#rrggbb, alpha) of the stroke or fill paint, None when it paints nothing."""
    v = style.get(key, "none")
    if v.strip().lower() == "currentcolor":
        v = style.get("color", "black")
    return _colour(v)


def opacity(value: str | None) -> float:
    if value is None:
        return 1.0
    v = value.strip()
    try:
        x = float(v[:-1]) / 100 if v.endswith("%") else float(v)
    except ValueError:
        return 1.0
    return min(max(x, 0.0), 1.0)


_SELECTOR = re.compile(r"[\w\-]*(?:[.#][\w\-]+)?|\*")


def _uncomment(text: str) -> str:
    """CSS without its comments (an unclosed one runs to the end)."""
    parts = []
    pos = 0
    while (start := text.find("/*", pos)) >= 0:
        parts.append(text[pos:start])
        end = text.find("*/", start + 2)
        if end < 0:
            return "".join(parts)
        pos = end + 2
    parts.append(text[pos:])
    return "".join(parts)


def _rules(text: str) -> list[tuple[str, str]]:
    """(selector, body) of each `selector { body }`; at-rules' blocks are skipped."""
    out = []
    pos = 0
    while (open_ := text.find("{", pos)) >= 0:
        close = text.find("}", open_ + 1)
        if close < 0:
            break
        sel = text[pos:open_]
        if "{" in text[open_ + 1:close]:        # a nested block (@media): skip it whole
            depth, k = 0, open_
            while k < len(text):
                depth += {"{": 1, "}": -1}.get(text[k], 0)
                k += 1
                if depth == 0:
                    break
            pos = k
            continue
        if not sel.strip().startswith("@"):
            out.append((sel, text[open_ + 1:close]))
        pos = close + 1
    return out


class Stylesheet:
    """The rules of the document's <style> elements for the simple selectors SVG editors
    write: `*`, `tag`, `.class`, `#id`, `tag.class` (others are ignored)."""

    def __init__(self, root: Element) -> None:
        self.rules: dict[str, list[tuple[int, dict[str, str]]]] = {}
        for el in root.iter():
            if local(el.tag) == "style" and el.text:
                self._add(el.text)

    def _add(self, text: str) -> None:
        for sel, body in _rules(_uncomment(text)):
            decls = declarations(body)
            for one in sel.split(","):
                one = one.strip()
                if not one or not _SELECTOR.fullmatch(one):
                    continue
                spec = 2 if "#" in one else 1 if "." in one else 0
                self.rules.setdefault(one, []).append((spec, decls))

    def matching(self, tag: str, elem: Element) -> Declarations:
        if not self.rules:
            return {}, {}
        keys = ["*", tag]
        for cls in (elem.get("class") or "").split():
            keys += [f".{cls}", f"{tag}.{cls}"]
        if elem.get("id"):
            keys.append(f"#{elem.get('id')}")
        found = sorted((spec, n, decls) for n, k in enumerate(keys)
                       for spec, decls in self.rules.get(k, ()))
        normal: dict[str, str] = {}
        important: dict[str, str] = {}
        for _, _, (norm, imp) in found:
            normal.update(norm)
            important.update(imp)
        return normal, important


Declarations = tuple[dict[str, str], dict[str, str]]     # (normal, !important)


def declarations(text: str) -> Declarations:
    normal: dict[str, str] = {}
    important: dict[str, str] = {}
    for part in text.split(";"):
        key, sep, value = part.partition(":")
        if sep and len(value) <= MAX_VALUE:
            m = _IMPORTANT.search(value)
            target = important if m else normal
            target[key.strip().lower()] = (value[:m.start()] if m else value).strip()
    return normal, important


def cascade(elem: Element, tag: str, parent: dict[str, str],
            sheet: Stylesheet) -> tuple[dict[str, str], dict[str, str]]:
    """(inherited style for the element and its children, the element's own properties)."""
    own = {k: v for k, v in elem.attrib.items() if k in PROPERTIES and len(v) <= MAX_VALUE}
    sheet_normal, sheet_important = sheet.matching(tag, elem)
    inline_normal, inline_important = declarations(elem.attrib.get("style", ""))
    for decls in (sheet_normal, inline_normal, sheet_important, inline_important):
        own.update(decls)
    if "marker" in own:                 # the shorthand sets all three
        for key in ("marker-start", "marker-mid", "marker-end"):
            own.setdefault(key, own["marker"])
    style = parent
    changed = {k: v for k, v in own.items() if k in INHERITED and v.strip() != "inherit"}
    if "font-size" in changed:
        changed["font-size"] = font_size(changed["font-size"], parent.get("font-size", "16"))
    if changed:
        style = {**parent, **changed}
    return style, own


def font_size(value: str, parent: str) -> str:
    """A font-size as px: em, ex and % of the parent's (itself px), keywords as CSS sizes
    them; one that cannot be read is the parent's."""
    try:
        base = float(parent)
    except ValueError:
        base = 16.0
    v = value.strip().lower()
    if v in FONT_SIZES:
        return repr(FONT_SIZES[v])
    if v in ("larger", "smaller"):
        return repr(base * 1.2 if v == "larger" else base / 1.2)
    try:
        return repr(length(v, base, font=base))
    except ValueError:
        return repr(base)
