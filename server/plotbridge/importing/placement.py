"""Placement: scale, quarter-turn rotation, translation, and fitting to paper."""

from __future__ import annotations

from dataclasses import dataclass

from plotbridge.papers import PAPERS

from .models import ImportFailed, ImportOptions, MachineProfile

Bounds = tuple[float, float, float, float]   # min_x, min_y, max_x, max_y


def paper_size(name: str) -> tuple[float, float]:
    """Width and height in mm of "A4", "a4-landscape", "letter-portrait", ..."""
    base, _, orient = name.strip().upper().partition("-")
    if base not in PAPERS or orient not in ("", "PORTRAIT", "LANDSCAPE"):
        raise ImportFailed.one(422, f"unknown paper '{name}': use A6, A5, A4, A3 or letter, "
                                    "optionally with -landscape")
    w, h = PAPERS[base]
    return (h, w) if orient == "LANDSCAPE" else (w, h)


@dataclass(frozen=True)
class Transform:
    """x' = s·R(x) + t with R a rotation by `quarter` quarter turns counter-clockwise."""

    scale: float = 1.0
    quarter: int = 0
    tx: float = 0.0
    ty: float = 0.0

    def linear(self, x: float, y: float) -> tuple[float, float]:
        s = self.scale
        q = self.quarter
        if q == 0:
            return s * x, s * y
        if q == 1:
            return -s * y, s * x
        if q == 2:
            return -s * x, -s * y
        return s * y, -s * x

    def apply(self, x: float, y: float) -> tuple[float, float]:
        lx, ly = self.linear(x, y)
        return lx + self.tx, ly + self.ty

    @property
    def identity(self) -> bool:
        return self == Transform()

    def box(self, b: Bounds) -> Bounds:
        xs, ys = zip(*(self.apply(x, y) for x in (b[0], b[2]) for y in (b[1], b[3])),
                     strict=True)
        return min(xs), min(ys), max(xs), max(ys)


def needs_bounds(options: ImportOptions) -> bool:
    return bool(options.paper or options.fit or options.rotate % 360)


def check_options(options: ImportOptions) -> None:
    errors = []
    if options.rotate % 90:
        errors.append("rotate must be 0, 90, 180 or 270")
    if not options.scale > 0:
        errors.append("scale must be positive")
    if options.margin < 0:
        errors.append("margin must not be negative")
    if not options.tolerance >= 0:
        errors.append("tolerance must not be negative")
    if not options.feed > 0:
        errors.append("feed must be positive")
    if errors:
        raise ImportFailed(422, [{"line": None, "message": m} for m in errors])


def placement(bounds: Bounds | None, options: ImportOptions,
              profile: MachineProfile) -> Transform:
    """The transform from source millimetres to machine coordinates. `bounds` is the
    drawn extent of the source (needed when rotating or fitting)."""
    check_options(options)
    quarter = (options.rotate // 90) % 4
    lin = Transform(options.scale, quarter)
    if bounds is None:
        return Transform(options.scale, quarter, options.dx, options.dy)
    b = lin.box(bounds)
    w, h = b[2] - b[0], b[3] - b[1]
    if options.paper or options.fit:
        m = options.margin
        if options.paper:
            pw, ph = paper_size(options.paper)
            if pw > profile.width + 1e-6 or ph > profile.height + 1e-6:
                raise ImportFailed.one(
                    422, f"paper {options.paper} ({pw:g} x {ph:g} mm) is larger than the "
                         f"work area ({profile.width:g} x {profile.height:g} mm); "
                         "try the other orientation")
        else:
            pw, ph = profile.width, profile.height
        bw, bh = pw - 2 * m, ph - 2 * m
        if bw <= 0 or bh <= 0:
            raise ImportFailed.one(422, f"margin {m:g} mm leaves no room on the paper")
        scale = options.scale
        if options.fit:
            k = min(bw / w if w > 0 else float("inf"), bh / h if h > 0 else float("inf"))
            if k == float("inf"):
                k = 1.0
            scale *= k
            lin = Transform(scale, quarter)
            b = lin.box(bounds)
            w, h = b[2] - b[0], b[3] - b[1]
        elif w > bw + 1e-6 or h > bh + 1e-6:
            raise ImportFailed.one(
                422, f"the drawing ({w:.1f} x {h:.1f} mm) does not fit {options.paper} with "
                     f"{m:g} mm margins ({bw:.1f} x {bh:.1f} mm); use fit or a smaller scale")
        tx = m + (bw - w) / 2 - b[0]
        ty = m + (bh - h) / 2 - b[1]
        return Transform(scale, quarter, tx + options.dx, ty + options.dy)
    # Rotation turns the drawing in place: its lower-left corner stays where it was.
    sx, sy = options.scale * bounds[0], options.scale * bounds[1]
    return Transform(options.scale, quarter, sx - b[0] + options.dx, sy - b[1] + options.dy)
