"""import_file / import_pattern: from an upload to program.gcode + preview.json."""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np

from .coords import read_coords
from .detect import check_text, detect_format, line_chunks, numbered_lines
from .gcode import read_ops, sniff_dialect
from .models import ErrorLog, ImportFailed, ImportOptions, ImportResult, MachineProfile
from .ops import (
    ARC,
    MOVE,
    PALETTE,
    PEN,
    Layer,
    Stroke,
    arc_extent,
    layers_to_ops,
    ops_to_layers,
    single_moves,
)
from .optimize import optimize_strokes, time_budget, travel
from .patterns import pattern_strokes
from .penplace import placed_pens
from .placement import Bounds, Transform, needs_bounds, placement
from .program import ProgramWriter
from .svg import read_svg

PROGRAM = "program.gcode"
PREVIEW = "preview.json"
SNIFF_CHARS = 1 << 20   # how much of a G-code file decides its pen dialect


def drawn_bounds(ops: Iterable[tuple]) -> Bounds | None:
    """Extent of the pen-down moves of a stream of ops (None when nothing is drawn)."""
    b = [math.inf, math.inf, -math.inf, -math.inf]
    x = y = 0.0
    down = False
    for op in single_moves(ops):
        kind = op[0]
        if kind == PEN:
            down = op[2]
        elif kind == MOVE or kind == ARC:
            if down:
                if kind == MOVE:
                    xs, ys = (x, op[2]), (y, op[3])
                    ext = (min(xs), min(ys), max(xs), max(ys))
                else:
                    ext = arc_extent(x, y, op[2], op[3], op[4], op[5], op[7])
                b = [min(b[0], ext[0]), min(b[1], ext[1]), max(b[2], ext[2]), max(b[3], ext[3])]
            x, y = op[2], op[3]
    return None if b[0] > b[2] else (b[0], b[1], b[2], b[3])


def strokes_bounds(strokes: list[Stroke]) -> Bounds | None:
    pts = [p for s in strokes for p in s]
    if not pts:
        return None
    xs, ys = zip(*pts, strict=True)
    return min(xs), min(ys), max(xs), max(ys)


def write_program(ops_factory: Callable[[], Iterator[tuple]], fmt: str, dest_dir: Path,
                  transform: Transform, profile: MachineProfile, errors: ErrorLog,
                  travel_before: float | None = None,
                  fills: list[Stroke] | None = None) -> ImportResult:
    """Writes program.gcode and preview.json atomically from the ops; raises ImportFailed
    (leaving nothing behind) when the ops or the errors found while writing say so."""
    dest_dir.mkdir(parents=True, exist_ok=True)
    program = dest_dir / PROGRAM
    preview = dest_dir / PREVIEW
    tmp_program = dest_dir / f".{PROGRAM}.part"
    tmp_preview = dest_dir / f".{PREVIEW}.part"
    writer: ProgramWriter | None = None
    try:
        with tmp_program.open("wb") as out:
            writer = ProgramWriter(out, transform, profile, errors)
            writer.preview.fills = fills or []
            writer.write_ops(ops_factory())
            writer.finish()
        errors.raise_if_any()
        if writer.pen_lifts == 0:
            raise ImportFailed.one(422, "nothing to draw: the input has no pen-down moves")
        bounds = writer.bounds_dict()
        writer.preview.write(tmp_preview, bounds)   # while the estimate's last batch runs
        writer.planner.wait()
        os.replace(tmp_program, program)
        os.replace(tmp_preview, preview)
    except BaseException:
        if writer is not None:
            writer.planner.close()
        for p in (tmp_program, tmp_preview):
            p.unlink(missing_ok=True)
        raise
    planner = writer.planner
    after = writer.travel_mm
    timeline = planner.timeline(writer.line, round(planner.time, 3))
    return ImportResult(
        format=fmt,
        program_path=program,
        preview_path=preview,
        lines_total=writer.line,
        estimate_s=round(planner.time, 3),
        bounds=bounds,
        stats={
            "pen_down_mm": round(writer.pen_down_mm, 3),
            "travel_before_mm": round(after if travel_before is None else travel_before, 3),
            "travel_after_mm": round(after, 3),
            "pen_lifts": writer.pen_lifts,
        },
        timeline=timeline,
        layers=layer_table(writer.layers, timeline),
        warnings=list(errors.warnings),
        substitutions=list(errors.substitutions),
    )


def layer_table(layers: list[dict], timeline: list[tuple[int, float]]) -> list[dict]:
    """The writer's layers with each one's estimated time (from the timeline)."""
    if not timeline:
        return layers
    lines = [0] + [n for n, _ in timeline]
    secs = [0.0] + [t for _, t in timeline]

    def at(line: int) -> float:
        return float(np.interp(line, lines, secs))

    return [{**lay, "estimate_s": round(at(lay["last_line"]) - at(lay["first_line"] - 1), 1)}
            for lay in layers]


def import_layers(layers: list[Layer], fmt: str, dest_dir: Path, options: ImportOptions,
                  profile: MachineProfile, errors: ErrorLog, feed: float | None = None,
                  optimize: bool = True) -> ImportResult:
    """Places, optionally optimizes (within each layer, never across), and writes a
    drawing given as layers of pen-down polylines, in layer order."""
    errors.raise_if_any()
    bounds = strokes_bounds([s for lay in layers for s in lay.strokes])
    if bounds is None:
        raise ImportFailed.one(422, "nothing to draw")
    transform = placement(bounds, options, profile)
    placed = [Layer(lay.name, lay.colour, [[transform.apply(x, y) for x, y in s]
                                           for s in lay.strokes]) for lay in layers]
    fills = [[transform.apply(x, y) for x, y in ring] for lay in layers for ring in lay.fills]
    before = travel([s for lay in placed for s in lay.strokes])
    if optimize:
        deadline = time.monotonic() + time_budget(sum(len(lay.strokes) for lay in placed))
        start = (0.0, 0.0)
        for lay in placed:
            lay.strokes = optimize_strokes(lay.strokes, options.tolerance, deadline, start)
            if lay.strokes:
                start = lay.strokes[-1][-1]
    placed = [lay for lay in placed if lay.strokes]
    draw_feed = feed or options.feed
    return write_program(lambda: layers_to_ops(placed, draw_feed), fmt, dest_dir, Transform(),
                         profile, errors, travel_before=before, fills=fills)


def import_strokes(strokes: list[Stroke], fmt: str, dest_dir: Path, options: ImportOptions,
                   profile: MachineProfile, errors: ErrorLog,
                   optimize: bool = True) -> ImportResult:
    """A drawing of one layer (coordinates lists, patterns)."""
    return import_layers([Layer("layer 1", PALETTE[0], strokes)], fmt, dest_dir, options,
                         profile, errors, optimize=optimize)


def import_gcode(source: Path, encoding: str, dest_dir: Path, options: ImportOptions,
                 profile: MachineProfile) -> ImportResult:
    errors = ErrorLog()
    if options.pen_dialect == "auto" and options.servo_down_angle is None:
        with source.open("r", encoding=encoding, newline=None) as f:
            options = replace(options, pen_dialect=sniff_dialect(f.read(SNIFF_CHARS)))
    try:
        def ops(warn: bool = True) -> Iterator[tuple]:
            return placed_pens(read_ops(line_chunks(source, encoding), options, errors),
                               errors if warn else None)
        ops()  # validates the dialect options before reading
    except ValueError as e:
        raise ImportFailed.one(422, str(e)) from None
    if options.optimize:
        layers, feed = ops_to_layers(ops(), min(options.tolerance, 0.01) or 0.01)
        return import_layers(layers, "gcode", dest_dir, options, profile, errors,
                             feed=feed or None)
    bounds = None
    if needs_bounds(options):
        bounds = drawn_bounds(ops(warn=False))
        errors.raise_if_any()
        if bounds is None:
            raise ImportFailed.one(422, "nothing to draw: the input has no pen-down moves")
    transform = placement(bounds, options, profile)
    return write_program(ops, "gcode", dest_dir, transform, profile, errors)


def import_file(source: Path, filename: str, dest_dir: Path, options: ImportOptions,
                profile: MachineProfile) -> ImportResult:
    """Turns an uploaded file into dest_dir/program.gcode and dest_dir/preview.json."""
    source = Path(source)
    dest_dir = Path(dest_dir)
    encoding = check_text(source)
    fmt = detect_format(source, filename, encoding)
    if fmt == "gcode":
        return import_gcode(source, encoding, dest_dir, options, profile)
    optimize = options.optimize is not False
    errors = ErrorLog()
    if fmt == "svg":
        return import_layers(read_svg(source, options, errors), fmt, dest_dir, options, profile,
                             errors, optimize=optimize)
    strokes = read_coords(numbered_lines(source, encoding), errors)
    return import_strokes(strokes, fmt, dest_dir, options, profile, errors, optimize=optimize)


def import_pattern(name: str, dest_dir: Path, options: ImportOptions,
                   profile: MachineProfile) -> ImportResult:
    """Writes one of the built-in test patterns (see PATTERNS)."""
    strokes = pattern_strokes(name)
    return import_strokes(strokes, "pattern", Path(dest_dir), options, profile, ErrorLog(),
                          optimize=options.optimize is not False)
