"""SVG bytes to an element tree, safely.

A DOCTYPE is accepted (Illustrator and many editors write one). Its internal subset
may declare general entities whose values are plain text (Illustrator declares its
namespace URIs that way); those are expanded here, with the expansion bounded, before
the XML parser sees the document, and the DOCTYPE is removed. External entities
(SYSTEM/PUBLIC), parameter entities (`%name;`), entities whose value refers to another
entity or holds markup, and any other declaration that defines content are refused
with a message. The parser then runs with DTDs forbidden, so nothing is ever fetched
from a file or the network and no entity is expanded by the parser itself.
"""

from __future__ import annotations

import re
from xml.etree.ElementTree import Element

from defusedxml import ElementTree as SafeET
from defusedxml.common import DefusedXmlException

from .models import ImportFailed

MAX_EXPANSION = 4 << 20      # bytes an entity expansion may add to the document
MAX_ENTITIES = 256
_DOCTYPE = re.compile(rb"<!DOCTYPE\s+[^\s\[>]+(?:\s+(?:PUBLIC|SYSTEM)\s*(?:\"[^\"]*\"|'[^']*')"
                      rb"(?:\s*(?:\"[^\"]*\"|'[^']*'))?)?\s*"
                      rb"(?:\[(?P<subset>(?:[^\]\"']|\"[^\"]*\"|'[^']*')*)\]\s*)?>", re.S)
_DECL = re.compile(rb"<!(?P<kind>ENTITY|ELEMENT|ATTLIST|NOTATION)\b"
                   rb"(?P<body>(?:[^>\"']|\"[^\"]*\"|'[^']*')*)>|"
                   rb"<!--.*?-->|<\?.*?\?>|\s+", re.S)
_ENTITY = re.compile(rb"\s*(?P<pct>%\s*)?(?P<name>[A-Za-z_][\w.\-:]*)\s*"
                     rb"(?P<rest>.*)", re.S)
_VALUE = re.compile(rb"(?:\"(?P<d>[^\"]*)\"|'(?P<s>[^']*)')\s*", re.S)
_REF = re.compile(rb"&([A-Za-z_][\w.\-:]*);")
_XML_BUILTIN = {b"lt", b"gt", b"amp", b"quot", b"apos"}


def _line_of(data: bytes, offset: int) -> int:
    return data.count(b"\n", 0, offset) + 1


def _entities(subset: bytes, data: bytes, base: int) -> dict[bytes, bytes]:
    """The plain-text general entities of an internal subset; anything else refused."""
    out: dict[bytes, bytes] = {}
    pos = 0
    while pos < len(subset):
        m = _DECL.match(subset, pos)
        if m is None:
            line = _line_of(data, base + pos)
            snippet = subset[pos:pos + 30].decode("utf-8", "replace")
            raise ImportFailed.one(422, f"SVG refused: DOCTYPE holds '{snippet}', which is not "
                                        "a declaration this importer accepts", line)
        pos = m.end()
        kind = m.group("kind")
        if kind is None or kind in (b"ELEMENT", b"ATTLIST", b"NOTATION"):
            continue        # comments, processing instructions, content models: no effect
        line = _line_of(data, base + m.start())
        e = _ENTITY.match(m.group("body"))
        if e is None:
            raise ImportFailed.one(422, "SVG refused: malformed ENTITY declaration", line)
        name = e.group("name").decode("utf-8", "replace")
        if e.group("pct"):
            raise ImportFailed.one(422, f"SVG refused: parameter entity '%{name};' is not "
                                        "accepted (only plain-text entities are)", line)
        rest = e.group("rest")
        if re.match(rb"(?:SYSTEM|PUBLIC)\b", rest):
            raise ImportFailed.one(422, f"SVG refused: external entity '{name}' is not "
                                        "accepted: the importer never reads other files or "
                                        "the network", line)
        v = _VALUE.fullmatch(rest)
        if v is None:
            raise ImportFailed.one(422, f"SVG refused: malformed value of entity '{name}'",
                                   line)
        value = v.group("d") if v.group("d") is not None else v.group("s")
        if b"&" in value or b"%" in value:
            raise ImportFailed.one(422, f"SVG refused: entity '{name}' refers to another "
                                        "entity or character reference; only plain-text "
                                        "entity values are accepted", line)
        if b"<" in value:
            raise ImportFailed.one(422, f"SVG refused: entity '{name}' holds markup; only "
                                        "plain-text entity values are accepted", line)
        if len(out) >= MAX_ENTITIES:
            raise ImportFailed.one(422, f"SVG refused: more than {MAX_ENTITIES} entities", line)
        out.setdefault(e.group("name"), value)
    return out


def _escape(value: bytes) -> bytes:
    return (value.replace(b"&", b"&amp;").replace(b"<", b"&lt;")
            .replace(b'"', b"&quot;").replace(b"'", b"&apos;"))


def strip_doctype(data: bytes) -> bytes:
    """The document without its DOCTYPE, its plain-text entities expanded."""
    start = data.find(b"<!DOCTYPE")
    if start < 0:
        return data
    m = _DOCTYPE.match(data, start)
    if m is None:
        raise ImportFailed.one(422, "SVG refused: malformed DOCTYPE", _line_of(data, start))
    subset = m.group("subset")
    entities = _entities(subset, data, m.start("subset")) if subset else {}
    body = data[m.end():]
    # The DOCTYPE's lines are kept as blank lines: parse errors keep the file's line numbers.
    head = data[:start] + b"\n" * m.group(0).count(b"\n")
    if not entities:
        return head + body
    added = 0

    def expand(ref: re.Match) -> bytes:
        nonlocal added
        name = ref.group(1)
        value = entities.get(name)
        if value is None:
            return ref.group(0)     # the parser reports an undefined one
        added += len(value)
        if added > MAX_EXPANSION:
            raise ImportFailed.one(422, f"SVG refused: entity expansion larger than "
                                        f"{MAX_EXPANSION >> 20} MB")
        return _escape(value)

    return head + _REF.sub(expand, body)


def parse_svg_xml(data: bytes) -> Element:
    """The root element of an SVG document, or ImportFailed saying what and where."""
    data = strip_doctype(data)
    try:
        root = SafeET.fromstring(data, forbid_dtd=True, forbid_entities=True,
                                 forbid_external=True)
    except DefusedXmlException as e:
        raise ImportFailed.one(422, f"SVG refused: {e.__class__.__name__}: DTD features "
                                    "other than plain-text entities are not accepted") from None
    except SafeET.ParseError as e:
        line = e.position[0] if getattr(e, "position", None) else None
        raise ImportFailed.one(422, f"SVG is not well-formed XML: {e}", line) from None
    except RecursionError:
        raise ImportFailed.one(422, "SVG refused: elements nested too deeply") from None
    return root
