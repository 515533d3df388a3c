"""Is the upload text, in which encoding, and which format is it?"""

from __future__ import annotations

import codecs
import re
from collections.abc import Iterator
from pathlib import Path

from ..native.textcheck import first_control
from .models import ImportFailed

GCODE_EXT = {".gcode", ".nc", ".gc", ".ngc", ".tap", ".g"}
SVG_EXT = {".svg"}
COORD_EXT = {".txt", ".coords", ".xy", ".csv"}
_CHUNK = 1 << 20
_SNIFF = 1 << 16
_GCODE_LINE = re.compile(r"^[ \t]*(?:N\d+[ \t]*)?[GM]\d", re.I | re.M)
_NUMBER_LINE = re.compile(r"^\s*[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?\s*$")


def check_text(path: Path) -> str:
    """The encoding to read `path` with ("utf-8" or "latin-1"); refuses binary and empty
    files."""
    decoder = codecs.getincrementaldecoder("utf-8")()
    utf8 = True
    blank = True
    with path.open("rb") as f:
        if f.read(4)[:2] in (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE):
            raise ImportFailed.one(415, "UTF-16 text is not accepted: save the file as UTF-8")
        f.seek(0)
        offset = 0
        while chunk := f.read(_CHUNK):
            bad = first_control(chunk)
            if bad >= 0:
                raise ImportFailed.one(415, f"not a text file: control byte "
                                            f"0x{chunk[bad]:02x} at offset {offset + bad}")
            if blank and chunk.strip():
                blank = False
            # ASCII with no sequence open before it is UTF-8 (and 10 times faster to
            # tell than decoding it)
            if utf8 and not (chunk.isascii() and not decoder.getstate()[0]):
                try:
                    decoder.decode(chunk)
                except UnicodeDecodeError:
                    utf8 = False
            offset += len(chunk)
    if blank:
        raise ImportFailed.one(422, "the file is empty")
    if utf8:
        try:
            decoder.decode(b"", final=True)
        except UnicodeDecodeError:
            utf8 = False
    return "utf-8" if utf8 else "latin-1"


def detect_format(path: Path, filename: str, encoding: str) -> str:
    """"gcode", "svg" or "coords": the content decides where it is clear, the name
    otherwise."""
    with path.open("r", encoding=encoding, errors="replace", newline=None) as f:
        head = f.read(_SNIFF)
    head = head.lstrip("\ufeff")
    stripped = head.lstrip()
    if stripped.startswith("<"):
        if re.search(r"<(?:[A-Za-z_][\w.-]*:)?svg[\s>]", head):
            return "svg"
        raise ImportFailed.one(415, "XML/HTML file that is not SVG: not an accepted format")
    ext = Path(filename).suffix.lower()
    lines = [ln for ln in head.splitlines()[:-1] or head.splitlines() if ln.strip()]
    if lines and all(_NUMBER_LINE.match(ln) for ln in lines[:200]):
        return "coords"
    if ext in GCODE_EXT or _GCODE_LINE.search(head):
        return "gcode"
    if ext in COORD_EXT:
        return "coords"
    if ext in SVG_EXT:
        raise ImportFailed.one(422, "the .svg file holds no <svg> element")
    raise ImportFailed.one(
        415, f"unknown format for '{filename}': expected G-code (.gcode .nc .gc .ngc .tap), "
             "SVG, or a coordinates list (one number per line)")


def numbered_lines(path: Path, encoding: str) -> Iterator[tuple[int, str]]:
    """(1-based line number, text) without line endings, streamed."""
    with path.open("r", encoding=encoding, newline=None) as f:
        for n, line in enumerate(f, 1):
            yield n, line.rstrip("\n")


def line_chunks(path: Path, encoding: str, size: int = 1 << 20) -> Iterator[str | bytes]:
    """Whole lines, each ending with a newline, about `size` characters at a time,
    streamed. A UTF-8 file's chunks are its bytes as they
    are (the text's UTF-8, which is what gcodescan.c reads: no decoding, counting and
    encoding again) while they hold no CR; from the first chunk with one, and for
    Latin-1 files, they are text with universal newlines (CR LF and CR read as LF)."""
    offset = 0
    if encoding == "utf-8":
        with path.open("rb") as f:
            while data := f.read(size):
                if not data.endswith(b"\n"):
                    data += f.readline()
                if b"\r" in data:
                    break
                if not data.endswith(b"\n"):
                    data += b"\n"
                yield data
                offset += len(data)
            else:
                return
    with path.open("r", encoding=encoding, newline=None) as f:
        f.seek(offset)      # a line's start: the decoder has nothing pending there
        while text := f.read(size):
            if not text.endswith("\n"):
                text += f.readline()
                if not text.endswith("\n"):
                    text += "\n"
            yield text
