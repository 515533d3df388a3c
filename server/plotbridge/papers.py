"""Paper sizes: the one table (the importer fits to them, the API checks names by it)."""

from __future__ import annotations

PAPERS: dict[str, tuple[float, float]] = {  # portrait width x height, mm
    "A6": (105.0, 148.0),
    "A5": (148.0, 210.0),
    "A4": (210.0, 297.0),
    "A3": (297.0, 420.0),
    "LETTER": (215.9, 279.4),
}

PAPER_PATTERN = "^(" + "|".join(sorted(PAPERS)) + ")(-(landscape|portrait))?$"
"""A paper name as the API accepts it (case-insensitive: compile with re.I)."""


def orient(name: str, width: float, height: float) -> tuple[str, str | None]:
    """A paper named without an orientation that is too large for the work area upright
    but fits on its side is turned to landscape: (the name to use, what was done or None)."""
    base, _, orientation = name.strip().upper().partition("-")
    if orientation or base not in PAPERS:
        return name, None
    w, h = PAPERS[base]

    def fits(a: float, b: float) -> bool:
        return a <= width + 1e-6 and b <= height + 1e-6

    if fits(w, h) or not fits(h, w):
        return name, None
    return f"{name}-landscape", (
        f"{name} upright ({w:g} x {h:g} mm) does not fit the work area "
        f"({width:g} x {height:g} mm): placed in landscape")
