"""Everything the server serves works offline: every HTML page and asset reachable
from /, /docs and /redoc is fetched, and no http(s):// reference leaves the host."""

from __future__ import annotations

import re
from urllib.parse import urljoin, urlsplit

import pytest

START = ("/", "/docs", "/redoc", "/docs/oauth2-redirect")
# Third-party bundles (fastapi-offline's Swagger UI and ReDoc) name URLs in their code:
# XML namespaces, JSON-schema ids, links in messages, ReDoc's sidebar logo. The pages
# that load them carry a Content-Security-Policy that lets the browser fetch from this
# server only, so none of those can be fetched; the policy is checked below.
BUNDLES = ("/docs/assets/swagger-ui-bundle.js", "/docs/assets/redoc.standalone.js")
VENDORED = "/docs/assets/"  # their stylesheet names namespaces inside data: URIs only
EXTERNAL = re.compile(r"https?://", re.I)
REFERENCES = (
    re.compile(r"""\s(?:src|href|action)=["']([^"']+)["']""", re.I),  # HTML attributes
    re.compile(r"""url\(\s*["']?([^"')]+)["']?\s*\)""", re.I),  # CSS
    re.compile(r"""@import\s+["']([^"']+)["']"""),  # CSS
    # ES modules: `import ... from "x"`, `export ... from "x"`, `import "x"`, `import("x")`
    re.compile(r"""^\s*(?:import|export)\b[^"';]*?\bfrom\s*["']([^"']+)["']""", re.M),
    re.compile(r"""\bimport\s*\(?\s*["']([^"']+)["']"""),
)
SAFE_SOURCES = {"'self'", "'unsafe-inline'", "data:", "blob:", "'none'"}


def references(text: str) -> set[str]:
    return {m.strip() for pattern in REFERENCES for m in pattern.findall(text)}


@pytest.mark.e2e
def test_every_page_and_asset_stays_on_the_host(server_virtual):
    client = server_virtual.client
    host = urlsplit(server_virtual.url).netloc
    queue, seen, leaving = list(START), set(), []
    pages_with_bundles = []
    while queue:
        path = queue.pop()
        if path in seen:
            continue
        seen.add(path)
        response = client.get(path)
        assert response.status_code == 200, f"{path}: {response.status_code}"
        kind = response.headers.get("content-type", "")
        if not kind.startswith(("text/", "application/javascript", "application/json")):
            continue
        text = response.text
        if not path.startswith(VENDORED):  # pages and the UI's own files: no external URL
            assert not EXTERNAL.search(text), f"{path}: {EXTERNAL.search(text)!r}"
        for ref in references(text):
            if ref.startswith(("data:", "#", "blob:", "javascript:")) or "${" in ref:
                continue
            target = urlsplit(urljoin(server_virtual.url + path, ref))
            if target.netloc != host:
                leaving.append(f"{path} -> {ref}")
            elif target.path not in seen and path not in BUNDLES:
                queue.append(target.path)
        if kind.startswith("text/html") and any(b in text for b in BUNDLES):
            pages_with_bundles.append((path, response.headers.get("content-security-policy")))
    assert not [ref for ref in leaving if not ref.startswith(BUNDLES)], leaving
    assert {"/docs", "/redoc", *BUNDLES, "/docs/assets/swagger-ui.css"} <= seen
    assert any(p.endswith(".js") and p.startswith("/js/") for p in seen), seen  # the web UI
    assert {path for path, _ in pages_with_bundles} == {"/docs", "/redoc"}
    for path, policy in pages_with_bundles:  # the bundles' own URLs can never be fetched
        assert policy, f"{path} has no Content-Security-Policy"
        for directive in policy.split(";"):
            name, *sources = directive.split()
            assert set(sources) <= SAFE_SOURCES, f"{path}: {name} allows {sources}"
    assert client.get("/openapi.json").json()["info"]["title"] == "plotbridge"
