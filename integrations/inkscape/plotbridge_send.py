#!/usr/bin/env python3
"""Inkscape extension: Extensions > plotbridge > Send to plotter.

Uploads the current document as SVG (its layers intact) to a plotbridge server
and reports the new job's estimate, or the server's errors, in Inkscape's
message box. Inkscape's own Python runs it, so it uses only inkex and the
standard library (not the plotbridge package).
"""

from __future__ import annotations

import json
import urllib.error
import urllib.request
import uuid
from typing import Any

import inkex
from lxml import etree

TIMEOUT_S = 120


def multipart(fields: dict[str, str], filename: str, content: bytes) -> tuple[bytes, str]:
    """A multipart/form-data body with the text fields and the file; (body, content type)."""
    boundary = f"plotbridge-{uuid.uuid4().hex}"
    filename = "".join(ch for ch in filename if ch.isprintable() and ch not in '"\\')
    parts = []
    for key, value in fields.items():
        parts.append(f'--{boundary}\r\nContent-Disposition: form-data; name="{key}"\r\n\r\n'
                     f"{value}\r\n".encode())  # fmt: skip
    parts.append(f'--{boundary}\r\nContent-Disposition: form-data; name="file"; '
                 f'filename="{filename}"\r\nContent-Type: image/svg+xml\r\n\r\n'.encode())
    parts += [content, f"\r\n--{boundary}--\r\n".encode()]
    return b"".join(parts), f"multipart/form-data; boundary={boundary}"


def server_errors(body: bytes) -> str:
    """The server's `detail` as lines to read (upload errors with their line numbers)."""
    try:
        detail = json.loads(body.decode("utf-8", "replace")).get("detail")
    except (ValueError, AttributeError):
        return body.decode("utf-8", "replace").strip()[:500]
    if isinstance(detail, dict) and isinstance(detail.get("errors"), list):
        return "\n".join(
            f"line {e.get('line')}: {e.get('message')}" if e.get("line") else str(e.get("message"))
            for e in detail["errors"]
        )  # fmt: skip
    return str(detail)


class SendToPlotbridge(inkex.EffectExtension):
    def add_arguments(self, pars: Any) -> None:
        pars.add_argument("--tab", default="send")
        pars.add_argument("--server", default="http://plotbridge.local:8000")
        pars.add_argument("--token", default="")
        pars.add_argument("--paper", default="")
        pars.add_argument("--fit", type=inkex.Boolean, default=False)
        pars.add_argument("--layers", default="")
        pars.add_argument("--start", type=inkex.Boolean, default=False)

    def effect(self) -> bool:
        server = self.options.server.strip().rstrip("/")
        token = self.options.token.strip()
        if not server.startswith(("http://", "https://")):
            raise inkex.AbortExtension(f"Server must be a URL like http://plotbridge.local:8000, "
                                       f"not {server!r}")  # fmt: skip
        if not token:
            raise inkex.AbortExtension("Enter the server's token (on its console, or in the "
                                       "file 'token' in its data directory).")  # fmt: skip
        job = self.upload(server, token)
        estimate = job.get("estimate_s") or 0
        minutes, seconds = divmod(round(estimate), 60)
        lines = [f"Job {job['id']} '{job['name']}' is {job['state']} on {server}.",
                 f"Estimated plotting time: {minutes} min {seconds} s."]  # fmt: skip
        if job.get("start_error"):
            lines.append(f"It did not start: {job['start_error']}")
        if job.get("actions"):
            lines.append("It allows now: " + ", ".join(job["actions"]) + ".")
        inkex.errormsg("\n".join(lines))
        return False  # the document is unchanged: Inkscape keeps it as it is

    def upload(self, server: str, token: str) -> dict[str, Any]:
        root = self.document.getroot()
        name = root.get(inkex.addNS("docname", "sodipodi")) or "inkscape.svg"
        fields = {"name": name}
        if self.options.paper:
            fields["paper"] = self.options.paper
        if self.options.fit:
            fields["fit"] = "true"
        if self.options.layers.strip():
            fields["layers"] = self.options.layers.strip()
        if self.options.start:
            fields["start"] = "true"
        svg = etree.tostring(self.document, xml_declaration=True, encoding="UTF-8")
        body, kind = multipart(fields, name if name.endswith(".svg") else f"{name}.svg", svg)
        request = urllib.request.Request(
            f"{server}/api/jobs", data=body, method="POST",
            headers={"Authorization": f"Bearer {token}", "Content-Type": kind},
        )  # fmt: skip
        try:
            with urllib.request.urlopen(request, timeout=TIMEOUT_S) as response:
                return json.loads(response.read())
        except urllib.error.HTTPError as exc:
            raise inkex.AbortExtension(f"The server refused the drawing ({exc.code}):\n"
                                       f"{server_errors(exc.read())}") from exc  # fmt: skip
        except (urllib.error.URLError, OSError) as exc:
            reason = getattr(exc, "reason", exc)
            raise inkex.AbortExtension(f"Cannot reach {server}: {reason}") from exc


if __name__ == "__main__":
    SendToPlotbridge().run()
