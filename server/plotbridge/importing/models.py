"""The importer's public data types (see docs/INTERNALS.md, "Importer API")."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from ..grbl import build_of
from ..motion.timing import GRBL_LINE_S, GRBL_PLANNER_BLOCKS, LINE_S

MAX_ERRORS = 100


@dataclass
class MachineProfile:
    """What the estimate and the work-area check need to know about the machine."""

    width: float = 300.0
    height: float = 220.0
    max_rate: tuple[float, float] = (6000.0, 6000.0)
    accel: tuple[float, float] = (1000.0, 1000.0)
    junction_deviation: float = 0.02
    arc_tolerance: float = 0.002
    pen_settle_s: float = 0.15
    steps_per_mm: tuple[float, float] = (80.0, 80.0)
    corexy: bool = False
    planner_blocks: int = 0    # blocks the board's planner holds; 0: the library's board's depth
    baud: int = 115200  # serial speed: bounds how fast lines reach the planner (0: no bound)
    plan_block_s: float = LINE_S  # firmware time from a line's arrival to its ok (motion/timing.py)
    line_numbers: bool = True  # lines go with an N word (the board reports `Ln:`: ours does)
    build: str | None = None  # the board profile whose motion library runs (None: the default)

    @classmethod
    def from_settings(cls, settings: dict[int, float]) -> MachineProfile:
        d = cls()

        def get(n: int, default: float) -> float:
            return float(settings.get(n, default))

        return cls(
            width=get(130, d.width),
            height=get(131, d.height),
            max_rate=(get(110, d.max_rate[0]), get(111, d.max_rate[1])),
            accel=(get(120, d.accel[0]), get(121, d.accel[1])),
            junction_deviation=get(11, d.junction_deviation),
            arc_tolerance=get(12, d.arc_tolerance),
            pen_settle_s=get(62, d.pen_settle_s * 1000.0) / 1000.0,
            steps_per_mm=(get(100, d.steps_per_mm[0]), get(101, d.steps_per_mm[1])),
            corexy=bool(get(63, 0)),
        )

    @classmethod
    def stock_grbl(cls, settings: dict[int, float], baud: int = 115200) -> MachineProfile:
        """The estimate's profile for a stock GRBL 1.1 board with these $ settings: the
        same motion library, configured with GRBL's planner depth and line time, lines
        sent without N words (motion/timing.py)."""
        return replace(cls.from_settings(settings), planner_blocks=GRBL_PLANNER_BLOCKS,
                       plan_block_s=GRBL_LINE_S, baud=baud, line_numbers=False)

    @classmethod
    def for_board(cls, settings: dict[int, float], firmware: str | None,
                  profile: str | None = None, planner_blocks: int = 0,
                  line_numbers: bool | None = None) -> MachineProfile:  # fmt: skip
        """The estimate's profile for a plotter (Plotter.import_model): its $ settings,
        its `$I` version (stock GRBL's model when the build is not ours, our firmware's
        when it is or is unknown), its board profile, and what its `$I` said once it was
        read: the planner's depth and whether it reports `Ln:` (lines then go with N)."""
        build = build_of(firmware)
        if build is not None and build.lower() != "plotbridge":
            board = cls.stock_grbl(settings)
        else:
            board = replace(cls.from_settings(settings), build=profile)
        if planner_blocks:
            board = replace(board, planner_blocks=planner_blocks)
        if line_numbers is not None:
            board = replace(board, line_numbers=line_numbers)
        return board


@dataclass
class ImportOptions:
    name: str | None = None
    paper: str | None = None
    margin: float = 10.0
    fit: bool = False
    rotate: int = 0
    scale: float = 1.0
    dx: float = 0.0
    dy: float = 0.0
    optimize: bool | None = None
    tolerance: float = 0.02
    layers: list[str] | None = None
    pen_dialect: str = "auto"
    z_threshold: float = 0.0
    servo_down_angle: float | None = None
    feed: float = 3000.0  # mm/min for drawing moves of SVG, coordinates and patterns
    fill: str = "outline"  # SVG fills: "outline" (filled-only shapes), "none", "hatch"
    hatch_spacing: float = 0.5   # mm between hatch lines (the default pen's width)
    hatch_angle: float = 45.0    # degrees, counter-clockwise on the page
    hatch_cross: bool = False    # a second hatch at right angles
    # per layer, group or fill colour: {name: {fill, hatch_spacing, hatch_angle,
    # hatch_cross}} overriding the four above (fillplan.py; fields.layer_fills checks it)
    layer_fill: dict[str, dict] | None = None
    font: str = "futural"        # single-stroke font for SVG text (svgtext.FONTS)
    clip_to_page: bool = True    # SVG: drop what lies outside the document's page


@dataclass
class ImportResult:
    format: str
    program_path: Path
    preview_path: Path
    lines_total: int
    estimate_s: float
    bounds: dict[str, float]
    stats: dict[str, float]
    timeline: list[tuple[int, float]] = field(default_factory=list)
    # [{"name", "colour", "first_line", "last_line", "strokes", "pen_down_mm",
    #   "estimate_s"}] in plotting order (docs/INTERNALS.md, "Layers")
    layers: list[dict] = field(default_factory=list)
    warnings: list[dict] = field(default_factory=list)     # [{"line", "message"}]
    # SVG text set in a substitute font: [{"element", "text", "font", "substitute"}]
    substitutions: list[dict] = field(default_factory=list)


class ImportFailed(Exception):
    """The input was refused: `status` is 413, 415 or 422; `errors` name what and where."""

    def __init__(self, status: int, errors: list[dict]):
        self.status = status
        self.errors = errors[:MAX_ERRORS]
        first = self.errors[0]["message"] if self.errors else "import failed"
        more = f" (+{len(errors) - 1} more)" if len(errors) > 1 else ""
        super().__init__(f"{status}: {first}{more}")

    def __reduce__(self):   # picklable across the server's worker processes
        return (type(self), (self.status, self.errors))

    @classmethod
    def one(cls, status: int, message: str, line: int | None = None) -> ImportFailed:
        return cls(status, [{"line": line, "message": message}])


class ErrorLog:
    """Collects errors with line numbers, keeping the first MAX_ERRORS and counting the rest."""

    def __init__(self) -> None:
        self.errors: list[dict] = []
        self.count = 0
        self.warnings: list[dict] = []
        self.warning_count = 0
        self.substitutions: list[dict] = []

    def warn(self, line: int | None, message: str, times: int = 1) -> None:
        """Something dropped or changed that the user should know about (`times` times);
        the import goes on. Repeats of one message are counted, not listed again."""
        self.warning_count += times
        for w in self.warnings:
            if w["message"] == message:
                w["count"] = w.get("count", 1) + times
                return
        if len(self.warnings) < MAX_ERRORS:
            self.warnings.append({"line": line, "message": message}
                                 | ({"count": times} if times > 1 else {}))

    def add(self, line: int | None, message: str) -> None:
        self.count += 1
        if len(self.errors) < MAX_ERRORS:
            self.errors.append({"line": line, "message": message})

    def __bool__(self) -> bool:
        return self.count > 0

    def raise_if_any(self) -> None:
        if not self.count:
            return
        errors = list(self.errors)
        if self.count > len(errors):
            errors[-1] = {"line": None,
                          "message": f"{self.count - len(errors) + 1} more errors not shown"}
        raise ImportFailed(422, errors)
