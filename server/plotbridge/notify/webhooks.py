"""Webhooks: every notice POSTed as JSON to each configured URL.

URLs come from `plotbridge serve --webhook URL` (fixed while the server runs)
and from the settings (`DATA_DIR/webhooks.json`, edited through
`/api/settings/webhooks`). Each URL has its own `Delivery` (ordered, bounded,
retried); a slow or dead receiver holds back only its own queue. The events waiting
are kept in the server's database (`Outbox`) and delivered after a restart; those of
a URL that is no webhook any more are dropped with a log line.
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import httpx

from plotbridge import __version__
from plotbridge.auth import write_private
from plotbridge.events import Message
from plotbridge.notify.delivery import Delivery
from plotbridge.notify.notices import NoticeWatcher
from plotbridge.notify.outbox import Outbox, Pending
from plotbridge.notify.targets import LocalTarget, refuse_local

log = logging.getLogger("plotbridge.notify")

MAX_URLS = 16
MAX_URL_LENGTH = 2048
POST_TIMEOUT_S = 10.0  # a receiver that takes longer counts as down (retried)
SETTINGS_FILE = "webhooks.json"


def check_url(url: str) -> str:
    """The URL if a webhook can be posted to it; else ValueError saying why."""
    if not isinstance(url, str) or not url.strip():
        raise ValueError("a webhook URL must not be empty")
    url = url.strip()
    if len(url) > MAX_URL_LENGTH:
        raise ValueError(f"webhook URL longer than {MAX_URL_LENGTH} characters")
    if not url.isprintable() or any(ch.isspace() for ch in url):
        raise ValueError(f"webhook URL {url[:80]!r} contains spaces or control characters")
    try:
        parts = urlsplit(url)
        _ = parts.port  # raises on a port that is no number or out of range
    except ValueError as exc:
        raise ValueError(f"webhook URL {url[:80]!r}: {exc}") from exc
    if parts.scheme.lower() not in ("http", "https"):
        raise ValueError(f"webhook URL {url[:80]!r}: only http:// and https:// URLs can be "
                         f"posted to, not {parts.scheme or 'a URL without a scheme'}")  # fmt: skip
    if not parts.hostname:
        raise ValueError(f"webhook URL {url[:80]!r} names no host")
    return url


def check_urls(urls: list[str]) -> list[str]:
    """Checked, without repeats, at most MAX_URLS."""
    checked = list(dict.fromkeys(check_url(url) for url in urls))
    if len(checked) > MAX_URLS:
        raise ValueError(f"at most {MAX_URLS} webhook URLs, not {len(checked)}")
    return checked


def read_settings(path: Path) -> list[str]:
    """The saved URLs; none (with a log line saying why) when the file cannot be used."""
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        return []
    except (OSError, ValueError) as exc:
        log.error("%s cannot be read (%s): no webhooks from the settings", path, exc)
        return []
    try:
        if not isinstance(data, dict) or not isinstance(data.get("urls"), list):
            raise ValueError('expected {"urls": [...]}')
        return check_urls(data["urls"])
    except ValueError as exc:
        log.error("%s: %s: no webhooks from the settings", path, exc)
        return []


def write_settings(path: Path, urls: list[str]) -> None:
    """Replace the file whole (a crash leaves the old or the new one)."""
    scratch = path.with_name(path.name + ".tmp")
    write_private(scratch, json.dumps({"urls": urls}, indent=1) + "\n")
    os.replace(scratch, path)


class Webhooks:
    def __init__(self, fixed: list[str], data_dir: Path, db_path: Path,
                 allow_local: bool = False, **delivery: Any) -> None:  # fmt: skip
        self.fixed = check_urls(fixed)
        self.allow_local = allow_local  # settings URLs may reach this machine (targets.py)
        self.path = data_dir / SETTINGS_FILE
        self.saved = read_settings(self.path)
        self._delivery = delivery  # Delivery's limit and delays (tests shorten them)
        self._outbox = Outbox(db_path)
        self._watcher = NoticeWatcher()
        self._deliveries: dict[str, Delivery] = {}
        self._client: httpx.AsyncClient | None = None
        self._lock = asyncio.Lock()

    # ---- lifecycle --------------------------------------------------------------------

    async def start(self) -> None:
        headers = {"User-Agent": f"plotbridge/{__version__}"}
        waiting = await self._outbox.open()
        for url in set(waiting) - set(self.urls):
            log.warning("webhook %s is no longer configured: its %d waiting events are "
                        "dropped", url, len(waiting.pop(url)))  # fmt: skip
            self._outbox.forget(url)
        self._client = httpx.AsyncClient(timeout=POST_TIMEOUT_S, headers=headers,
                                         follow_redirects=False)  # fmt: skip
        self._reconcile(waiting)
        for url in self.urls:
            log.info("webhook: events go to %s", url)

    async def close(self) -> None:
        for delivery in list(self._deliveries.values()):
            await delivery.close()
        self._deliveries.clear()
        await self._outbox.close()  # the events still waiting stay for the next start
        if self._client is not None:
            await self._client.aclose()
            self._client = None

    @property
    def urls(self) -> list[str]:
        return list(dict.fromkeys([*self.fixed, *self.saved]))

    # ---- the hub's subscriber ---------------------------------------------------------

    def publish(self, message: Message) -> None:
        """The event hub's subscriber: never waits (see Delivery.put)."""
        for notice in self._watcher.feed(message):
            body = notice.body()
            for delivery in self._deliveries.values():
                delivery.put(notice.event, body)

    # ---- settings -------------------------------------------------------------------------

    def view(self) -> dict[str, Any]:
        """The settings API's answer."""
        rows = []
        for url in self.urls:
            delivery = self._deliveries.get(url)
            figures = delivery.figures if delivery else None
            rows.append({
                "url": url, "source": "option" if url in self.fixed else "settings",
                "queued": delivery.queued if delivery else 0,
                "delivered": figures.delivered if figures else 0,
                "retries": figures.retries if figures else 0,
                "dropped": figures.dropped if figures else 0,
                "refused": figures.refused if figures else 0,
                "last_error": figures.last_error if figures else None,
            })  # fmt: skip
        return {"urls": list(self.saved), "fixed": list(self.fixed), "webhooks": rows}

    async def replace(self, urls: list[str]) -> dict[str, Any]:
        """New saved URLs (ValueError when one is unusable). A URL kept keeps its queue."""
        checked = check_urls(urls)
        if not self.allow_local:
            for url in checked:
                await refuse_local(url)
        async with self._lock:
            await asyncio.to_thread(write_settings, self.path, checked)
            self.saved = checked
            for url in set(self._deliveries) - set(self.urls):
                await self._deliveries.pop(url).close()
                self._outbox.forget(url)
            self._reconcile()
        log.info("webhook URLs in the settings: %s", ", ".join(checked) or "none")
        return self.view()

    def _reconcile(self, waiting: dict[str, list[Pending]] | None = None) -> None:
        if self._client is None:
            return
        for url in self.urls:
            if url not in self._deliveries:
                delivery = Delivery(url, self._post, self._outbox, (waiting or {}).get(url),
                                    **self._delivery)  # fmt: skip
                delivery.start()
                self._deliveries[url] = delivery

    async def _post(self, url: str, body: bytes, headers: dict[str, str]) -> int:
        assert self._client is not None
        if not self.allow_local and url not in self.fixed:
            try:
                await refuse_local(url)
            except LocalTarget as exc:
                raise httpx.ConnectError(str(exc)) from None
        response = await self._client.post(url, content=body, headers=headers)
        return response.status_code
