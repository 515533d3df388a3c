"""Static checks of web/: text from uploads can only reach the page as text."""

from __future__ import annotations

import re
from pathlib import Path

WEB = Path(__file__).resolve().parents[2] / "web"
HTML_SINKS = re.compile(
    r"innerHTML|outerHTML|insertAdjacentHTML|document\.write|createContextualFragment"
)


def test_no_html_parsing_sinks_in_the_ui():
    offenders = [
        f"{path.relative_to(WEB)}:{n}: {line.strip()}"
        for path in sorted(WEB.rglob("*.js"))
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if HTML_SINKS.search(line)
    ]
    assert offenders == []


def test_every_module_import_resolves():
    imports = re.compile(r"""^import .* from "(\.[^"]+)";$""", re.M)
    missing = [
        f"{path.relative_to(WEB)} imports {target}"
        for path in sorted(WEB.rglob("*.js"))
        for target in imports.findall(path.read_text())
        if not (path.parent / target).resolve().is_file()
    ]
    assert missing == []
