"""Helpers shared by the importer's unit tests."""

from __future__ import annotations

from pathlib import Path

from plotbridge.importing import ImportOptions, ImportResult, MachineProfile, import_file


def run_import(tmp_path: Path, text: str | bytes, name: str = "job.gcode",
               profile: MachineProfile | None = None, **options) -> ImportResult:
    src = tmp_path / ("src_" + name)
    if isinstance(text, str):
        src.write_text(text, encoding="utf-8")
    else:
        src.write_bytes(text)
    return import_file(src, name, tmp_path / "out", ImportOptions(**options),
                       profile or MachineProfile())


def program_lines(result: ImportResult) -> list[str]:
    return result.program_path.read_text().splitlines()


def drawn_strokes(lines: list[str]) -> list[list[tuple[float, float]]]:
    """Pen-down polylines of a normalized program with linear moves only."""
    strokes: list[list[tuple[float, float]]] = []
    x = y = 0.0
    down = False
    for line in lines:
        if line == "M3":
            down = True
            strokes.append([(x, y)])
        elif line == "M5":
            down = False
        elif line.startswith(("G0 ", "G1 ")):
            words = {w[0]: float(w[1:]) for w in line.split()[1:]}
            x, y = words["X"], words["Y"]
            if down:
                strokes[-1].append((x, y))
    return [s for s in strokes if len(s) > 1]
