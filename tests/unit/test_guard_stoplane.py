"""The stop lane (guard/stoplane.py) and the acceptor's first look at a head
(guard/acceptor.py), with the guard's real checks (a real people.Access on a store in a
temporary directory) and a recording stop verb."""

from __future__ import annotations

import json
import socket

import pytest
from plotbridge.access import Role
from plotbridge.errors import Refused
from plotbridge.guard.acceptor import Acceptor, may_be_stop
from plotbridge.guard.middleware import Checks
from plotbridge.guard.stoplane import LANE, NEED_MORE, StopLane
from plotbridge.people import Access, PeopleStore

from tests.fixtures.waits import settle

TOKEN = "lane-test-token-0123456"


@pytest.fixture
async def lane(tmp_path):
    stops: list[tuple] = []

    def stop(name, every, source, origin):
        if name == "nope":
            raise Refused(404, "no plotter named 'nope'")
        stops.append((name, every, source, origin))
        return {"status": "stopped"}

    store = PeopleStore(tmp_path / "plotbridge.db")
    store.add_person("kid", Role.viewer)
    viewer_key = store.add_key("wall-panel", Role.viewer)
    access = Access(store, TOKEN)
    lane = StopLane()
    lane.bind(Checks(access), stop)
    lane.stops = stops
    lane.session = access.new_session("kid", "person")  # a viewer's login
    lane.viewer_key = viewer_key
    yield lane
    await access.close()


def audited(lane) -> list[tuple]:
    """(who, action, page) of the audit log, oldest first (read after the writes before)."""
    access = lane.checks.access
    entries = access._writer.submit(lambda: list(access.store.audit_all())).result()
    return [(e["who"], e["action"], (e["detail"] or {}).get("page")) for e in entries]


def head(path: str, *headers: str, body: bytes = b"") -> bytes:
    lines = [f"POST {path} HTTP/1.1", "Host: 127.0.0.1", *headers]
    return ("\r\n".join(lines) + "\r\n\r\n").encode() + body


def status(answer: bytes) -> tuple[int, dict]:
    start, _, body = answer.partition(b"\r\n\r\n")
    assert b"connection: close" in start
    return int(start.split(b" ")[1]), json.loads(body)


def test_a_stop_with_the_token_is_acted_on_and_answered(lane):
    auth = f"Authorization: Bearer {TOKEN}"
    assert status(lane.answer(head("/api/machine/estop", auth))) == (202, {"status": "stopped"})
    assert status(lane.answer(head("/api/estop", auth, "X-Plotbridge-Page: p-1")))[0] == 202
    assert status(lane.answer(head("/api/plotters/left/machine/estop", auth)))[0] == 202
    assert lane.stops == [(None, False, "REST", None), (None, True, "REST", "p-1"),
                          ("left", False, "REST", None)]  # fmt: skip
    assert status(lane.answer(head("/api/plotters/nope/machine/estop", auth)))[0] == 404


def test_every_role_may_stop_in_the_lane(lane):
    """STOP is everyone's: a viewer's key and a viewer's session stop there too."""
    key = f"Authorization: Bearer {lane.viewer_key}"
    assert status(lane.answer(head("/api/machine/estop", key)))[0] == 202
    cookie = f"Cookie: plotbridge_session={lane.session}"
    assert status(lane.answer(head("/api/estop", cookie, "X-Plotbridge: 1",
                                   "X-Plotbridge-Page: p-2")))[0] == 202  # fmt: skip
    assert len(lane.stops) == 2
    assert audited(lane) == [("key wall-panel", "POST /api/machine/estop", None),
                             ("kid", "POST /api/estop", "p-2")]  # fmt: skip


def test_what_the_guard_would_refuse_goes_on_to_the_app(lane):
    cookie = f"Cookie: plotbridge_session={lane.session}"
    for request in (
        head("/api/machine/estop"),  # no token: the app answers 401
        head("/api/machine/estop", "Authorization: Bearer wrong-token-000000"),
        head("/api/machine/estop", cookie),  # a cookie without our page's header (CSRF)
        head("/api/machine/estop", cookie, "Origin: http://evil.example"),
        head("/api/machine/estop", f"Authorization: Bearer {TOKEN}", "Content-Length: 5000"),
        head("/api/machine/estop", f"Authorization: Bearer {TOKEN}",
             "Transfer-Encoding: chunked"),
        head("/api/machine/home", f"Authorization: Bearer {TOKEN}"),  # not a stop
    ):  # fmt: skip
        assert lane.answer(request) is None, request
    assert lane.stops == []
    assert status(lane.answer(head("/api/estop", cookie, "X-Plotbridge: 1")))[0] == 202


def test_a_small_body_is_read_before_the_answer(lane):
    auth = f"Authorization: Bearer {TOKEN}"
    partial = head("/api/estop", auth, "Content-Length: 2", body=b"{")
    assert lane.answer(partial) == NEED_MORE and lane.stops == []
    assert status(lane.answer(partial + b"}"))[0] == 202


def test_the_acceptor_keeps_only_what_may_become_a_stop():
    assert may_be_stop(b"") and may_be_stop(b"PO") and may_be_stop(b"POST /api/")
    assert may_be_stop(b"POST /api/estop HTTP/1.1\r\nHost")
    assert not may_be_stop(b"GET /api/health HTTP/1.1\r\n")
    assert not may_be_stop(b"POST /api/jobs HTTP/1.1\r\n")
    assert not may_be_stop(b"X")


async def test_a_stop_sent_with_its_connection_is_answered_by_the_accept_itself(lane):
    """The acceptor acts on a whole stop that came with its connection: no transport,
    no hand-over; any other request is handed over with its bytes still unread."""
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(8)
    listener.setblocking(False)
    handed, abandoned = [], []
    saved = (LANE.checks, LANE.stop)
    LANE.bind(lane.checks, lane.stop)
    acceptor = Acceptor(listener, lambda peer: True, lambda sock, peer: handed.append(sock),
                        abandoned.append)  # fmt: skip
    try:
        with socket.create_connection(listener.getsockname()) as client:
            client.sendall(head("/api/machine/estop", f"Authorization: Bearer {TOKEN}"))
            await settle(lambda: abandoned, what="the stop's connection closed")
            client.settimeout(5)
            assert status(client.recv(4096))[0] == 202
        assert lane.stops == [(None, False, "REST", None)] and handed == []
        other = b"GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"
        with socket.create_connection(listener.getsockname()) as client:
            client.sendall(other)
            await settle(lambda: handed, what="the request handed over")
            handed[0].setblocking(True)
            assert handed[0].recv(4096) == other
            handed[0].close()
        assert len(abandoned) == 1
    finally:
        acceptor.close()
        LANE.bind(*saved)
