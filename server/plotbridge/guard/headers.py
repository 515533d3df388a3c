"""Security headers added to every HTTP response."""

from __future__ import annotations

# Only the server's own scripts and styles; no inline code, no framing, no plugins.
CSP = (
    "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; "
    "connect-src 'self'; object-src 'none'; base-uri 'none'; form-action 'self'; "
    "frame-ancestors 'none'"
)
COMMON: tuple[tuple[bytes, bytes], ...] = (
    (b"x-content-type-options", b"nosniff"),
    (b"referrer-policy", b"no-referrer"),
    (b"x-frame-options", b"DENY"),
)
# /docs is FastAPI's Swagger page: its scripts come from a CDN and it has an inline one.
DOCS_PATHS = ("/docs", "/docs/oauth2-redirect")


def security_headers(path: str) -> list[tuple[bytes, bytes]]:
    csp = "frame-ancestors 'none'" if path in DOCS_PATHS else CSP
    return [*COMMON, (b"content-security-policy", csp.encode())]
