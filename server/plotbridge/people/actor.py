"""Who is acting, for the verbs that record it (an approval's "by"): set by the access
check for each request (api/deps.py) and by the WebSocket for each message (api/ws.py)."""

from __future__ import annotations

from contextvars import ContextVar

ACTOR: ContextVar[str] = ContextVar("plotbridge_actor", default="nobody")
