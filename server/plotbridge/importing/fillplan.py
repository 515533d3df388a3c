"""Which fill an SVG shape gets: the import's fill options, overridden per layer, group
or fill colour by `ImportOptions.layer_fill` (docs/INTERNALS.md, "Hatch per layer")."""

from __future__ import annotations

from dataclasses import dataclass

from .models import ErrorLog, ImportOptions
from .svgstyle import _colour


def named_colour(name: str) -> str | None:
    """The #rrggbb a layer-selection name spells, or None when it names no colour."""
    if name.strip().lower().startswith("url("):
        return None
    c = _colour(name)
    # svgelements reads any unknown name as black: only a black spelling is black
    black = name.strip().lower() in ("black", "#000", "#000000")
    return c[0] if c is not None and (c[0] != "#000000" or black) else None


@dataclass(frozen=True)
class Fill:
    mode: str           # "none", "outline" or "hatch"
    spacing: float      # mm between hatch lines
    angle: float        # degrees
    cross: bool


class FillPlan:
    def __init__(self, options: ImportOptions) -> None:
        self.default = Fill(options.fill, options.hatch_spacing, options.hatch_angle,
                            options.hatch_cross)
        self.by_name: dict[str, Fill] = {}
        self.by_colour: dict[str, Fill] = {}
        self.used: set[str] = set()
        for key, settings in (options.layer_fill or {}).items():
            d = self.default
            fill = Fill(settings.get("fill", "hatch"), settings.get("hatch_spacing", d.spacing),
                        settings.get("hatch_angle", d.angle),
                        settings.get("hatch_cross", d.cross))
            self.by_name[key] = fill
            colour = named_colour(key)
            if colour is not None:
                self.by_colour.setdefault(colour, fill)

    def fill_for(self, names: tuple[str, ...], colour: str | None) -> Fill:
        """The fill of a shape inside the groups `names` (outermost first, the layer's
        name among them) filled with `colour` (#rrggbb): the innermost named group's
        entry, else the fill colour's, else the import's own."""
        for name in reversed(names):
            fill = self.by_name.get(name)
            if fill is not None:
                self.used.add(name)
                return fill
        if colour is not None:
            fill = self.by_colour.get(colour)
            if fill is not None:
                self.used.update(k for k, f in self.by_name.items() if f is fill)
                return fill
        return self.default

    def warn_unused(self, errors: ErrorLog) -> None:
        for key in self.by_name:
            if key not in self.used:
                errors.warn(None, f"layer_fill: {key!r} matches no layer, group or fill "
                                  "colour of a filled shape; its settings were not used")
