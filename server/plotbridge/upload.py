"""Upload reception: stream the body to a temp file under a size limit.

Nothing is held whole in memory; the limit is enforced while reading, so an
oversized upload is refused after at most `limit` bytes.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

from pydantic import ValidationError
from starlette.datastructures import UploadFile
from starlette.formparsers import MultiPartException, MultiPartParser
from starlette.requests import Request

from plotbridge.importing.fields import import_fields
from plotbridge.models import Placement

CHUNK = 64 * 1024
TRUE = ("1", "true", "yes", "on")
FALSE = ("0", "false", "no", "off", "")
SNIFF = 8192


class UploadRefused(Exception):
    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


async def _limited(request: Request, limit: int) -> AsyncIterator[bytes]:
    received = 0
    async for chunk in request.stream():
        received += len(chunk)
        if received > limit:
            raise UploadRefused(413, f"upload larger than the limit of {limit // (1024 * 1024)} MB")
        yield chunk


def _check_length(request: Request, limit: int) -> None:
    length = request.headers.get("content-length")
    if length and length.isdecimal() and int(length) > limit + 64 * 1024:
        raise UploadRefused(413, f"upload larger than the limit of {limit // (1024 * 1024)} MB")


async def receive(request: Request, tmp_dir: Path, limit: int) -> tuple[Path | None, str, dict]:
    """The uploaded file (temp path or None), its client file name, and the form fields."""
    _check_length(request, limit)
    content_type = request.headers.get("content-type", "")
    if content_type.startswith("multipart/form-data"):
        return await _multipart(request, tmp_dir, limit)
    if content_type.startswith("application/x-www-form-urlencoded"):
        raise UploadRefused(422, "no file: send multipart field 'file' or the file as a raw body")
    fd, name = tempfile.mkstemp(dir=tmp_dir, prefix="upload-")
    path = Path(name)
    try:
        with os.fdopen(fd, "wb") as out:
            async for chunk in _limited(request, limit):
                out.write(chunk)
    except BaseException:
        os.unlink(path)
        raise
    return path, "", {}


async def _multipart(request: Request, tmp_dir: Path, limit: int) -> tuple[Path | None, str, dict]:
    parser = MultiPartParser(
        request.headers, _limited(request, limit),
        max_files=1, max_fields=30, max_part_size=64 * 1024,
    )  # fmt: skip
    try:
        form = await parser.parse()
    except MultiPartException as exc:
        raise UploadRefused(422, f"malformed multipart body: {exc.message}") from exc
    fields: dict[str, str] = {}
    upload: UploadFile | None = None
    try:
        for key, value in form.multi_items():
            if isinstance(value, UploadFile):
                if key != "file":
                    raise UploadRefused(422, f"unexpected file field {key!r}; use 'file'")
                upload = value
            else:
                fields[key] = value
        if upload is None:
            return None, "", fields
        fd, name = tempfile.mkstemp(dir=tmp_dir, prefix="upload-")
        with os.fdopen(fd, "wb") as out:
            while chunk := await upload.read(CHUNK):
                out.write(chunk)
        return Path(name), upload.filename or "", fields
    finally:
        await form.close()


def refuse_unusable(path: Path) -> None:
    """Empty and binary uploads get a clear refusal before any import work."""
    with path.open("rb") as handle:
        head = handle.read(SNIFF)
    if not head.strip():
        raise UploadRefused(422, "the upload is empty")
    if b"\x00" in head:
        raise UploadRefused(
            415, "the upload is a binary file; send G-code, SVG or coordinate text"
        )


def parse_upload_fields(params: dict[str, str]) -> tuple[dict[str, Any], dict[str, Any], bool]:
    """Import options, placement and `start` from form fields or query parameters."""

    def flag(key: str) -> bool | None:
        if key not in params:
            return None
        value = params[key].strip().lower()
        if value in TRUE:
            return True
        if value in FALSE:
            return False
        raise ValueError(f"{key}: expected true or false, got {params[key]!r}")

    raw: dict[str, Any] = {k: params[k] for k in Placement.model_fields if k in params}
    if "fit" in raw:
        raw["fit"] = flag("fit")
    try:
        placement = Placement(**raw)
    except ValidationError as exc:
        first = exc.errors(include_url=False)[0]
        field = ".".join(str(part) for part in first.get("loc", ()))
        raise ValueError(f"{field}: {first.get('msg')}") from exc
    options: dict[str, Any] = placement.model_dump()
    optimize = flag("optimize")
    if optimize is not None:
        options["optimize"] = optimize
    if params.get("layers"):
        options["layers"] = [part.strip() for part in params["layers"].split(",") if part.strip()]
    options.update(import_fields(params))
    placement_public = {k: v for k, v in options.items() if k in Placement.model_fields}
    return options, placement_public, bool(flag("start"))
