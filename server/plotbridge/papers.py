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
