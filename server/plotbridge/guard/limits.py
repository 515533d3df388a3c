"""Per-route request body bounds (bytes), checked before the app reads the body."""

from __future__ import annotations

import re

DEFAULT_BODY = 64 * 1024  # the largest JSON body any route takes
MULTIPART_SLACK = 64 * 1024  # form fields and boundaries around an upload's file

# (method, path pattern, bound). The first match wins; the upload route is bounded
# by the configured upload limit instead (see `body_limit`).
ROUTES: tuple[tuple[str, re.Pattern[str], int], ...] = (
    ("POST", re.compile(r"/api/login"), 1024),
    ("POST", re.compile(r"/api/logout"), 1024),
    ("POST", re.compile(r"/api/machine/(estop|unlock|home|pen|jog|motors)"), 1024),
    ("POST", re.compile(r"/api/machine/command"), 2048),
    ("PUT", re.compile(r"/api/machine/settings"), 16 * 1024),
    ("PATCH", re.compile(r"/api/jobs/[^/]+"), 4096),
    ("POST", re.compile(r"/api/jobs/[^/]+/(start|pause|resume|cancel|move)"), 1024),
)
UPLOAD = ("POST", "/api/jobs")


def body_limit(method: str, path: str, upload_limit: int) -> int:
    if (method, path.rstrip("/")) == UPLOAD:
        return upload_limit + MULTIPART_SLACK
    for route_method, pattern, limit in ROUTES:
        if method == route_method and pattern.fullmatch(path):
            return limit
    return DEFAULT_BODY
