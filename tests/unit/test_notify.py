"""Notifications: which hub messages make which notices, and how one URL's queue
delivers them (order, retries with backoff, bounds) to a fake receiver; the events
still waiting kept in SQLite across a restart; the settings API for the URLs."""

from __future__ import annotations

import asyncio
import json
import logging
import sqlite3
import time
from collections.abc import AsyncIterator
from pathlib import Path

import httpx
import pytest
from plotbridge.cli import webhooks_from_args
from plotbridge.config import ConfigError
from plotbridge.notify import Webhooks, check_url
from plotbridge.notify.delivery import Delivery
from plotbridge.notify.notices import NoticeWatcher
from plotbridge.notify.outbox import Outbox, Pending

from tests.fixtures.fake_app import make_app, serve_args, serving
from tests.fixtures.waits import settle

# ---- notices ------------------------------------------------------------------------


def job(state: str, **extra) -> dict:
    return {"type": "job", "job": {"id": "j1", "name": "cat", "plotter": "p1",
                                   "state": state, **extra}}  # fmt: skip


def machine(state: str, connected: bool = True, alarm: int | None = None) -> dict:
    return {"type": "machine", "plotter": "p1",
            "machine": {"connected": connected, "state": state, "alarm": alarm}}  # fmt: skip


def events(watcher: NoticeWatcher, *messages: dict) -> list[str]:
    return [n.event for m in messages for n in watcher.feed(m)]


def test_a_layered_job_tells_start_pen_changes_and_done_once_each():
    watcher = NoticeWatcher()
    change = {"layer": 2, "layers": 2, "message": "Layer 2 of 2, 'red': load its pen"}
    told = events(watcher, job("queued"), job("running"), job("running", progress=0.3),
                  job("pen_change", pen_change=change), job("pen_change"), job("running"),
                  job("paused"), job("running"), job("done"), job("done"))  # fmt: skip
    assert told == ["job_started", "pen_change", "job_done"]


def test_notice_bodies_name_plotter_job_time_and_say_what_happened():
    watcher = NoticeWatcher()
    watcher.feed(job("running"))
    change = {"layer": 2, "layers": 3, "message": "Layer 2 of 3, 'red': load its pen"}
    (notice,) = watcher.feed(job("pen_change", pen_change=change))
    body = notice.body()
    assert body["event"] == "pen_change" and body["plotter"] == "p1"
    assert body["job"] == {"id": "j1", "name": "cat", "state": "pen_change"}
    assert body["message"] == "Job 'cat' on p1: Layer 2 of 3, 'red': load its pen"
    assert body["details"]["layer"] == 2
    assert abs(body["timestamp"] - time.time()) < 5 and body["time"].endswith("+00:00")
    (later,) = watcher.feed(job("done"))
    assert later.body()["id"] != body["id"]
    json.dumps(body)  # plain JSON


def test_failed_stopped_and_interrupted_jobs_are_told_with_the_reason():
    watcher = NoticeWatcher()
    told = [n.body() for m in (job("running"), job("failed", error="line 4: error:20"))
            for n in watcher.feed(m)]  # fmt: skip
    assert told[-1]["event"] == "job_failed" and "line 4: error:20" in told[-1]["message"]
    for end in ("stopped", "cancelled", "interrupted"):
        watcher = NoticeWatcher()
        assert events(watcher, job("running"), job(end, error="why")) == ["job_started",
                                                                          "job_stopped"]
    # a waiting job cancelled never ran: nothing to tell
    assert events(NoticeWatcher(), job("waiting"), job("cancelled")) == []
    # resuming a stopped job starts it again
    watcher = NoticeWatcher()
    told = [n.message for m in (job("running"), job("stopped"), job("running"))
            for n in watcher.feed(m)]  # fmt: skip
    assert told[-1] == "Job 'cat' resumed on p1"


def test_alarm_and_link_lost_name_the_plotter_and_its_job():
    watcher = NoticeWatcher()
    # the board coming up in Alarm (homing required) is no news
    assert events(watcher, machine("Disconnected", False), machine("Alarm"), machine("Idle"),
                  job("running"), machine("Run")) == ["job_started"]  # fmt: skip
    (alarm,) = watcher.feed(machine("Alarm", alarm=2))
    assert alarm.event == "alarm" and "ALARM:2" in alarm.message
    assert alarm.job is not None and alarm.job.id == "j1"
    assert events(watcher, machine("Alarm", alarm=2)) == []  # still the same alarm
    assert events(watcher, machine("Idle"), job("interrupted")) == ["job_stopped"]
    (lost,) = watcher.feed(machine("Disconnected", False))
    assert lost.event == "link_lost" and lost.plotter == "p1"
    assert lost.job is not None and lost.job.state == "interrupted"  # the job it cut off
    assert events(watcher, machine("Disconnected", False)) == []


# ---- one URL's delivery -------------------------------------------------------------


class FakeReceiver:
    """Answers from a script (a status, or an exception to raise), then 200."""

    def __init__(self, *script: int | Exception) -> None:
        self.script = list(script)
        self.got: list[tuple[float, dict]] = []
        self.hang = asyncio.Event()
        self.hang.set()
        self.calls = 0

    async def post(self, url: str, body: bytes, headers: dict[str, str]) -> int:
        self.calls += 1
        await self.hang.wait()
        self.got.append((time.monotonic(), json.loads(body)))
        answer = self.script.pop(0) if self.script else 200
        if isinstance(answer, Exception):
            raise answer
        return answer

    def numbers(self) -> list[int]:
        return [body["n"] for _, body in self.got]


URL = "http://receiver.test/hook"


@pytest.fixture
async def outbox(tmp_path) -> AsyncIterator[Outbox]:
    outbox = Outbox(tmp_path / "plotbridge.db")
    assert await outbox.open() == {}
    yield outbox
    await outbox.close()


async def running(receiver: FakeReceiver, outbox: Outbox, waiting: list[Pending] | None = None,
                  **options) -> Delivery:  # fmt: skip
    delivery = Delivery(URL, receiver.post, outbox, waiting,
                        **{"first_delay": 0.05, "max_delay": 0.2, **options})  # fmt: skip
    delivery.start()
    return delivery


def kept(db: Path) -> list[tuple[str, int]]:
    """The outbox's rows as another process reads them: (url, the body's n)."""
    with sqlite3.connect(db) as conn:
        rows = conn.execute("SELECT url, body FROM webhook_outbox ORDER BY seq").fetchall()
    return [(url, json.loads(body)["n"]) for url, body in rows]


async def test_each_event_once_in_order(outbox):
    receiver = FakeReceiver()
    delivery = await running(receiver, outbox)
    for n in range(20):
        delivery.put("job_done", {"n": n})
    await settle(lambda: delivery.figures.delivered == 20)
    assert receiver.numbers() == list(range(20))
    assert delivery.queued == 0 and delivery.figures.retries == 0
    await delivery.close()


async def test_errors_are_retried_with_growing_delays_and_order_kept(outbox):
    receiver = FakeReceiver(500, httpx.ConnectError("refused"), httpx.ReadTimeout("slow"), 503)
    delivery = await running(receiver, outbox)
    delivery.put("job_started", {"n": 1})
    delivery.put("job_done", {"n": 2})
    await settle(lambda: delivery.figures.delivered == 2, within=5)
    assert receiver.numbers() == [1, 1, 1, 1, 1, 2]  # the first again until taken, then on
    gaps = [b[0] - a[0] for a, b in zip(receiver.got, receiver.got[1:5], strict=False)]
    assert gaps[0] >= 0.05 and gaps[1] >= 0.1 and gaps[2] >= 0.2 and gaps[3] >= 0.2  # capped
    assert delivery.figures.retries == 4 and delivery.figures.last_error is None
    await delivery.close()


async def test_a_receiver_refusing_an_event_for_good_is_not_asked_again(outbox):
    receiver = FakeReceiver(404)
    delivery = await running(receiver, outbox)
    delivery.put("alarm", {"n": 1})
    delivery.put("alarm", {"n": 2})
    await settle(lambda: delivery.queued == 0)
    assert receiver.numbers() == [1, 2]
    assert delivery.figures.refused == 1 and delivery.figures.delivered == 1
    await settle(lambda: kept(outbox.path) == [])  # refused for good: not kept either
    await delivery.close()


async def test_a_receiver_down_for_long_loses_the_oldest_events_only(outbox, caplog):
    receiver = FakeReceiver()
    receiver.hang.clear()  # the first post hangs
    delivery = await running(receiver, outbox, limit=5)
    delivery.put("job_done", {"n": 0})
    await settle(lambda: receiver.calls == 1)
    started = time.monotonic()
    for n in range(1, 12):
        delivery.put("job_done", {"n": n})
    assert time.monotonic() - started < 1  # put never waits (the receiver hangs for good)
    assert delivery.queued == 5 and delivery.figures.dropped == 7
    assert "dropped the oldest" in caplog.text
    await settle(lambda: kept(outbox.path) == [(URL, n) for n in range(7, 12)])  # on disk too
    receiver.hang.set()
    await settle(lambda: delivery.queued == 0)
    # the post under way (0) was already sent; the five newest follow in order
    assert receiver.numbers() == [0, 7, 8, 9, 10, 11]
    await settle(lambda: kept(outbox.path) == [])
    await delivery.close()


async def test_an_event_dropped_while_retried_is_not_sent_again(outbox):
    receiver = FakeReceiver(*([500] * 3))
    delivery = await running(receiver, outbox, limit=2, first_delay=0.1)
    delivery.put("job_done", {"n": 0})
    await settle(lambda: len(receiver.got) == 1)
    delivery.put("job_done", {"n": 1})
    delivery.put("job_done", {"n": 2})  # drops 0, which waits for its retry
    await settle(lambda: delivery.queued == 0, within=5)
    assert receiver.numbers()[0] == 0 and receiver.numbers()[1:] == [1, 1, 1, 2]
    await delivery.close()


# ---- the events waiting, across a restart -------------------------------------------


async def test_waiting_events_are_delivered_after_a_restart_in_order_once(outbox):
    receiver = FakeReceiver()
    receiver.hang.clear()  # the receiver is down: the first post never comes back
    delivery = await running(receiver, outbox)
    for n in range(4):
        delivery.put("job_done", {"n": n})
    await settle(lambda: receiver.calls == 1 and len(kept(outbox.path)) == 4)
    await delivery.close()  # the server stops (its post to the receiver cut off) ...
    await outbox.close()
    again = Outbox(outbox.path)  # ... and starts again
    waiting = await again.open()
    assert list(waiting) == [URL] and [p.event for p in waiting[URL]] == ["job_done"] * 4
    receiver = FakeReceiver()
    delivery = await running(receiver, again, waiting[URL])
    delivery.put("job_done", {"n": 4})  # new events queue behind the old ones
    await settle(lambda: delivery.figures.delivered == 5)
    assert receiver.numbers() == [0, 1, 2, 3, 4]
    await settle(lambda: kept(outbox.path) == [])
    await delivery.close()
    await again.close()
    assert await Outbox(outbox.path).open() == {}


async def test_more_events_kept_than_the_bound_drop_the_oldest_at_start(outbox, caplog):
    caplog.set_level(logging.INFO, "plotbridge.notify")
    for n in range(5):
        outbox.add(URL, "alarm", json.dumps({"n": n}).encode())
    await outbox.close()
    again = Outbox(outbox.path)
    waiting = await again.open()
    receiver = FakeReceiver()
    receiver.hang.clear()
    delivery = await running(receiver, again, waiting[URL], limit=3)
    assert delivery.queued == 3 and delivery.figures.dropped == 2
    assert "5 events from before the restart" in caplog.text
    assert "dropped the oldest" in caplog.text
    await settle(lambda: kept(outbox.path) == [(URL, 2), (URL, 3), (URL, 4)])
    await delivery.close()
    await again.close()


async def test_an_event_that_cannot_be_kept_is_logged_and_still_delivered(outbox, caplog):
    with sqlite3.connect(outbox.path) as conn:
        conn.execute("DROP TABLE webhook_outbox")  # the file went bad under the server
    receiver = FakeReceiver()
    delivery = await running(receiver, outbox)
    delivery.put("job_done", {"n": 0})
    await settle(lambda: delivery.figures.delivered == 1)
    await settle(lambda: "could not be kept" in caplog.text)
    assert "no such table: webhook_outbox" in caplog.text and receiver.numbers() == [0]
    await delivery.close()


async def test_events_of_a_url_no_longer_configured_are_dropped(tmp_path, caplog):
    db, kept_url, gone_url = tmp_path / "plotbridge.db", "http://127.0.0.1:9/kept", \
        "http://127.0.0.1:9/gone"  # fmt: skip
    outbox = Outbox(db)
    await outbox.open()
    outbox.add(gone_url, "job_done", b'{"n": 0}')
    outbox.add(kept_url, "job_done", b'{"n": 1}')
    await outbox.close()
    webhooks = Webhooks([], tmp_path, db, first_delay=30)  # port 9: refused, then waits
    webhooks.saved = [kept_url]
    await webhooks.start()
    assert f"webhook {gone_url} is no longer configured: its 1 waiting" in caplog.text
    assert webhooks.view()["webhooks"][0]["queued"] == 1
    await settle(lambda: kept(db) == [(kept_url, 1)])
    await webhooks.replace([])  # removing a URL drops its queue, on disk too
    await settle(lambda: kept(db) == [])
    await webhooks.close()


# ---- URLs and the settings API --------------------------------------------------------


@pytest.mark.parametrize("url, why", [
    ("ftp://host/x", "only http:// and https://"),
    ("file:///etc/passwd", "only http:// and https://"),
    ("host:8000/hook", "only http:// and https://"),
    ("http:///hook", "names no host"),
    ("http://host:99999/", "out of range"),
    ("http://ho st/", "spaces"),
    ("", "empty"),
])  # fmt: skip
def test_unusable_urls_are_refused_saying_why(url, why):
    with pytest.raises(ValueError, match=why):
        check_url(url)


def test_serve_takes_webhook_options_and_refuses_bad_ones(monkeypatch, capsys):
    monkeypatch.setenv("PLOTBRIDGE_WEBHOOKS", "http://a.test/1, http://a.test/1")
    args = serve_args("--webhook", "https://b.test/2")
    assert webhooks_from_args(args) == ("http://a.test/1", "https://b.test/2")
    with pytest.raises(SystemExit):
        serve_args("--webhook", "ftp://c.test/3")
    assert "only http:// and https://" in capsys.readouterr().err
    monkeypatch.setenv("PLOTBRIDGE_WEBHOOKS", "gopher://d.test/")
    with pytest.raises(ConfigError, match=r"PLOTBRIDGE_WEBHOOKS.*only http"):
        webhooks_from_args(serve_args())


def test_http_and_https_urls_are_taken():
    for url in ("http://127.0.0.1:9000/hook", "https://ntfy.example/plots?x=1"):
        assert check_url(url) == url


async def test_settings_refuse_this_machine_and_link_local_unless_allowed(tmp_path):
    app, _link = make_app(tmp_path, webhooks=("http://127.0.0.1:9/fixed",))  # the owner's
    async with serving(app) as client:
        for url, why in (("http://127.0.0.1:9/a", "loopback"), ("http://localhost:22/", "loopback"),
                         ("http://[::1]:9/", "loopback"), ("http://169.254.169.254/", "link-local"),
                         ("http://0.0.0.0:9/", "unspecified")):  # fmt: skip
            refused = await client.put("/api/settings/webhooks", json={"urls": [url]})
            assert refused.status_code == 422 and why in refused.text, (url, refused.text)
            assert "--webhook-allow-local" in refused.text


async def test_settings_api_saves_checks_and_shows_the_urls(tmp_path):
    app, _link = make_app(tmp_path, webhooks=("http://127.0.0.1:9/fixed",),
                          webhook_allow_local=True)  # fmt: skip
    async with serving(app) as client:
        shown = (await client.get("/api/settings/webhooks")).json()
        assert shown["fixed"] == ["http://127.0.0.1:9/fixed"] and shown["urls"] == []
        refused = await client.put("/api/settings/webhooks", json={"urls": ["ftp://x/"]})
        assert refused.status_code == 422
        assert "only http:// and https://" in refused.text
        urls = ["http://127.0.0.1:9/a", "https://example.test/b"]
        saved = await client.put("/api/settings/webhooks", json={"urls": urls})
        assert saved.status_code == 200, saved.text
        rows = saved.json()["webhooks"]
        assert [(r["url"], r["source"]) for r in rows] == [
            ("http://127.0.0.1:9/fixed", "option"), (urls[0], "settings"),
            (urls[1], "settings")]  # fmt: skip
        too_many = await client.put("/api/settings/webhooks",
                                    json={"urls": [f"http://h/{n}" for n in range(17)]})
        assert too_many.status_code == 422
    kept = json.loads((tmp_path / "webhooks.json").read_text())
    assert kept == {"urls": urls}
    assert (tmp_path / "webhooks.json").stat().st_mode & 0o077 == 0
    app, _link = make_app(tmp_path, webhook_allow_local=True)  # a restart reads them back
    async with serving(app) as client:
        assert (await client.get("/api/settings/webhooks")).json()["urls"] == urls
