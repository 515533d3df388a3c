"""The one error a component raises for a request it cannot do."""

from __future__ import annotations

from typing import Any


class Refused(Exception):
    """A request the current state does not allow; `status` is the HTTP status and
    `detail` the answer's `detail` (a message, or `{"errors": [...]}`)."""

    def __init__(self, status: int, detail: Any) -> None:
        super().__init__(detail)
        self.status = status
        self.detail = detail
