"""Helpers shared by the importer's unit tests."""

from __future__ import annotations

from pathlib import Path

from plotbridge.importing import ImportOptions, ImportResult, MachineProfile, import_file
from plotbridge.program.reader import drawn_strokes, read_program

__all__ = ["drawn_strokes", "program_lines", "run_import"]


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
    return [text for _, text in read_program(result.program_path)]

