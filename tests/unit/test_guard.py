"""The request guard (guard/), token rules (auth.py), log hygiene. Sessions and the
credential failure limit: test_people.py."""

from __future__ import annotations

import logging
import os
from typing import Any

import pytest
from plotbridge import auth as authmod
from plotbridge.auth import TokenRefused
from plotbridge.guard import logs
from plotbridge.guard.hosts import host_allowed, own_names

from tests.fixtures.fake_app import TOKEN, make_app, serving

OWN = {"host": "test", "origin": "http://test"}


async def call_raw(app: Any, method: str, path: str, headers: dict[str, str]) -> tuple[int, dict]:
    """One request straight through ASGI whose body must never be read."""
    sent: list[dict] = []

    async def receive() -> dict:
        raise AssertionError("the body was read")

    async def send(message: dict) -> None:
        sent.append(message)

    scope = {
        "type": "http", "method": method, "path": path, "raw_path": path.encode(),
        "query_string": b"", "root_path": "", "scheme": "http", "http_version": "1.1",
        "server": ("test", 80), "client": ("10.0.0.9", 5000),
        "headers": [(k.encode(), v.encode()) for k, v in headers.items()],
    }  # fmt: skip
    await app(scope, receive, send)
    start = next(m for m in sent if m["type"] == "http.response.start")
    return start["status"], {k.decode(): v.decode() for k, v in start["headers"]}


@pytest.fixture
async def guarded(tmp_path):
    app, _link = make_app(tmp_path)
    async with serving(app) as client:
        yield app, client


async def test_oversized_bodies_are_refused_before_auth_and_before_reading(guarded):
    app, _ = guarded
    for path in ("/api/login", "/api/machine/command"):
        status, headers = await call_raw(
            app, "POST", path, {"host": "test", "content-length": str(14_000_000)}
        )
        assert status == 413 and headers["connection"] == "close"
    # No token: 401 before a byte of the (in-bounds) body is read.
    status, _ = await call_raw(app, "POST", "/api/machine/command",
                               {"host": "test", "content-length": "100"})  # fmt: skip
    assert status == 401


async def test_a_body_without_length_is_counted_and_cut_at_the_bound(guarded):
    _, client = guarded

    async def chunks():
        for _ in range(100):
            yield b'{"token": "' + b"x" * 1000

    response = await client.post("/api/login", content=chunks(), headers={"authorization": ""})
    assert response.status_code == 413
    assert "1024 bytes" in response.json()["detail"]


async def test_validation_errors_never_echo_the_input(guarded):
    _, client = guarded
    body = {f"key{i}-" + "k" * 100: "SECRET" * 5 for i in range(90)}
    response = await client.put("/api/machine/settings", json={"settings": {}, **body})
    assert response.status_code == 422
    detail = response.json()["detail"]
    assert len(detail) <= 20 and "SECRET" not in response.text
    assert all(len(part) <= 64 for err in detail for part in map(str, err["loc"]))


async def test_security_headers_on_pages_and_answers(guarded):
    _, client = guarded
    for path in ("/api/health", "/api/machine", "/nope"):
        headers = (await client.get(path)).headers
        assert "script-src 'self'" in headers["content-security-policy"]
        assert "frame-ancestors 'none'" in headers["content-security-policy"]
        assert headers["x-content-type-options"] == "nosniff"
        assert headers["referrer-policy"] == "no-referrer"


async def test_foreign_host_names_are_refused(guarded):
    _, client = guarded
    assert (await client.get("/api/health", headers={"host": "evil.example"})).status_code == 400
    literal = await client.get("/api/health", headers={"host": "192.168.1.7:8000"})
    assert literal.status_code == 200
    names = own_names(["plotter.lan"])
    assert host_allowed("localhost:8000", names) and host_allowed("PLOTTER.lan.", names)
    assert host_allowed("[::1]:8000", names) and not host_allowed("evil.example", names)
    assert not host_allowed(None, names)


async def test_cookie_changes_need_our_origin_or_the_page_header(guarded):
    _, client = guarded
    login = await client.post("/api/login", json={"token": TOKEN}, headers={"authorization": ""})
    client.cookies.clear()
    session = login.cookies["plotbridge_session"]
    cookie = {"authorization": "", "cookie": f"plotbridge_session={session}"}

    async def estop(**headers: str) -> int:
        return (await client.post("/api/machine/estop", headers={**cookie, **headers})).status_code

    assert await estop() == 403  # a form or no-cors fetch: no Origin from an old browser, no header
    assert await estop(origin="http://test:8001") == 403  # another port: same site, other origin
    assert await estop(origin="http://evil.example", **{"x-plotbridge": "1"}) == 403
    assert await estop(origin="http://test") == 202
    assert await estop(**{"x-plotbridge": "1"}) == 202
    # Scripts with the token are not cookie-authenticated: no Origin needed.
    assert (await client.post("/api/machine/estop")).status_code == 202
    # Reading needs no Origin.
    assert (await client.get("/api/machine", headers=cookie)).status_code == 200


async def test_sessions_are_random_and_end_at_logout(guarded):
    _, client = guarded
    anon = {"authorization": ""}
    first = (await client.post("/api/login", json={"token": TOKEN}, headers=anon)).cookies
    client.cookies.clear()  # a second browser
    second = (await client.post("/api/login", json={"token": TOKEN}, headers=anon)).cookies
    client.cookies.clear()
    assert first["plotbridge_session"] != second["plotbridge_session"]
    cookie = {**anon, "cookie": f"plotbridge_session={first['plotbridge_session']}"}
    assert (await client.get("/api/machine", headers=cookie)).status_code == 200
    logout = await client.post("/api/logout", headers={**cookie, **OWN})
    assert logout.status_code == 204
    assert (await client.get("/api/machine", headers=cookie)).status_code == 401
    other = {**anon, "cookie": f"plotbridge_session={second['plotbridge_session']}"}
    assert (await client.get("/api/machine", headers=other)).status_code == 200


def test_short_tokens_are_refused(tmp_path):
    with pytest.raises(TokenRefused, match="16"):
        authmod.check_token_rules("secret")
    (tmp_path / "token").write_text("a\n")
    with pytest.raises(TokenRefused):
        authmod.load_or_create_token(tmp_path / "token")


def test_generated_token_file_is_private(tmp_path):
    token, made = authmod.load_or_create_token(tmp_path / "token")
    assert made and len(token) >= 16
    assert os.stat(tmp_path / "token").st_mode & 0o777 == 0o600
    assert authmod.load_or_create_token(tmp_path / "token") == (token, False)


def test_log_lines_escape_user_text_and_repeats_are_limited():
    assert logs.escape("a\nb\x00c") == "a\\nb\\x00c"
    assert logs.escape("plain text é") == "plain text é"
    formatter = logs.EscapingFormatter("%(message)s")
    record = logging.LogRecord("t", logging.INFO, "", 0, "job %s", ("evil\nFORGED",), None)
    assert formatter.format(record) == "job evil\\nFORGED"
    limit = logs.RateLimit()
    records = [logging.LogRecord("t", logging.WARNING, "", 0, "fell behind", (), None)
               for _ in range(1000)]  # fmt: skip
    assert sum(limit.filter(r) for r in records) == logs.PER_WINDOW


