"""Every API route and WebSocket message, called as each role and as nobody, against the one
table (plotbridge.access): a route missing from the table fails here."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient
from plotbridge.access import JOB_ACTIONS, PUBLIC, ROUTES, WS_MESSAGES, Role, may, may_act, rule
from plotbridge.jobs.imports import Importer
from starlette.websockets import WebSocketDisconnect

from tests.fixtures.fake_app import TOKEN, fake_import, make_app
from tests.fixtures.people import bearer, keys_per_role, served_routes

ROLES = [role.name for role in Role]
ACCESS_REFUSAL = "missing or wrong token"


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Importer, "_import", fake_import)
        yield from _world(make_app(tmp_path_factory.mktemp("matrix"))[0])


def _world(app):
    with TestClient(app) as client:
        keys = keys_per_role(app)
        files = {"file": ("a.gcode", "G1 X1 Y1\n")}
        others = client.post("/api/jobs", files=files, headers=bearer(TOKEN)).json()["id"]
        own = client.post("/api/jobs", files=files, headers=bearer(keys["submitter"])).json()
        yield client, keys, others, own["id"]


def concrete(template: str, job: str) -> str:
    if template.startswith("/api/plotters/{name}"):
        template = template.replace("{name}", "plotter1")
    return (template.replace("{job_id}", job).replace("{name}", "nobody-such")
            .replace("{pen}", "no-such-pen"))  # fmt: skip


def expanded() -> list[tuple[str, str, str | None]]:
    """Every HTTP route of the table; the job action route once per action."""
    found = []
    for method, template in sorted(ROUTES):
        if method == "WS":
            continue
        actions = sorted(JOB_ACTIONS) if "{action}" in template else [None]
        found += [(method, template, action) for action in actions]
    return found


def test_every_route_is_in_the_table(world):
    client, *_ = world
    assert served_routes(client.app) == set(ROUTES)


def test_every_route_as_each_role_and_as_nobody(world):
    client, keys, others, own = world
    wrong = []
    for method, template, action in expanded():
        need, owner_rule = rule(method, template, action)
        jobs = [(others, False), (own, True)] if owner_rule else [("no-such-job", False)]
        for job, owned in jobs:
            path = concrete(template, job).replace("{action}", action or "")
            answer = client.request(method, path, headers={"authorization": ""})
            if need is PUBLIC:
                if ACCESS_REFUSAL in answer.text[:100]:
                    wrong.append(("nobody", method, path, answer.status_code))
            elif answer.status_code != 401:
                wrong.append(("nobody", method, path, answer.status_code))
            for role in ROLES:
                answer = client.request(method, path, headers=bearer(keys[role]))
                allowed = may(Role[role], need, owned, owner_rule)
                if need is PUBLIC:
                    refused = answer.status_code == 403 or ACCESS_REFUSAL in answer.text[:100]
                else:
                    refused = answer.status_code in (401, 403)
                if allowed == refused:
                    wrong.append((role, method, path, answer.status_code))
                elif not allowed and role not in answer.json()["detail"]:
                    wrong.append((role, method, path, answer.text))
    assert not wrong


def test_ws_messages_as_each_role_and_as_nobody(world):
    client, keys, others, _ = world
    with pytest.raises(WebSocketDisconnect) as info, client.websocket_connect("/api/ws") as ws:
        ws.receive_text()
    assert info.value.code == 4401
    messages = {
        "estop": {}, "pause": {}, "resume": {}, "jog": {"dx": "bad"}, "command": {"line": "$$"},
        "job_action": {"job": others, "action": "start"},
    }  # fmt: skip
    assert set(messages) == set(WS_MESSAGES)
    for role in ROLES:
        with client.websocket_connect(f"/api/ws?token={keys[role]}") as ws:
            for kind, body in messages.items():
                ws.send_json({"type": kind, **body})
                answer = ws.receive_json()
                while answer["type"] not in ("ack", "error"):
                    answer = ws.receive_json()
                if kind == "job_action":
                    allowed = may_act(Role[role], "start", own=False)
                else:
                    allowed = Role[role] >= WS_MESSAGES[kind]
                refused = answer.get("status") == 403
                assert refused != allowed, (role, kind, answer)
