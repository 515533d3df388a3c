"""The WebSocket route: events out, commands in (docs/INTERNALS.md, "WebSocket messages")."""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from typing import Any

from fastapi import APIRouter, WebSocket
from pydantic import ValidationError

from plotbridge.access import WS_MESSAGES, Role, may_act
from plotbridge.api.deps import Components, Who, page_id
from plotbridge.errors import Refused
from plotbridge.models import JogBody
from plotbridge.people import Identity
from plotbridge.people.actor import ACTOR
from plotbridge.people.views import message_view
from plotbridge.ws import Client

log = logging.getLogger("plotbridge.api.ws")

WS_MESSAGE_MAX = 4096  # characters; the longest real message (a console line) is ~200
RESUME_WORDS = frozenset({"from", "overlap", "home"})  # a resume that may wait for homing
AWAITING = frozenset({"jog", "command", "job_action"})  # wait for the board: queued per client
WS_COMMANDS_WAITING = 16  # per WebSocket client: jog and console lines not yet answered

router = APIRouter()
Command = tuple[str, dict[str, Any]]


@router.websocket("/api/ws")
async def websocket(ws: WebSocket, who: Who) -> None:
    c: Components = ws.app.state.components
    assert who is not None  # access.ROUTES: a login is needed
    await ws.accept()  # the guard has checked the session or token, the Origin and the Host
    view = None if who.role == Role.admin else (lambda message: message_view(who, message))
    client = c.clients.add(ws, view)
    client.identity = who
    ACTOR.set(who.who)  # the tasks below act as this person (an approval's "by")
    untrack = c.access.track(who, lambda: _revoked(ws, client))
    for message in c.queue.snapshot_messages():
        c.clients.send(client, message)
    client.task = asyncio.create_task(client.pump())
    receiver = asyncio.create_task(_receive(c, ws, client))
    try:
        await asyncio.wait({client.task, receiver}, return_when=asyncio.FIRST_COMPLETED)
    finally:
        untrack()
        c.clients.remove(client)
        for task in (client.task, receiver):
            task.cancel()
        with contextlib.suppress(Exception):
            await ws.close()


def _revoked(ws: WebSocket, client: Client) -> None:
    """Logged out, rotated or revoked: close with 4401 at once."""
    asyncio.get_running_loop().create_task(_close(ws, 4401, "signed out or revoked"))
    if client.task is not None:
        client.task.cancel()


async def _close(ws: WebSocket, code: int, reason: str) -> None:
    with contextlib.suppress(Exception):
        await ws.close(code=code, reason=reason)


def refusal(c: Components, who: Identity, kind: Any,
            message: dict[str, Any]) -> dict[str, Any] | None:  # fmt: skip
    """The 403 answer when `who` may not send this message (plotbridge.access)."""
    need = WS_MESSAGES.get(kind) if isinstance(kind, str) else None
    if need is None:
        return None  # an unknown type: answered as such
    if kind == "job_action":
        job = message.get("job")
        action = str(message.get("action"))
        own = False
        if isinstance(job, str) and who.role == Role.submitter:
            try:
                own = c.queue.get(job).owner == who.who
            except Refused:
                return None  # an unknown job: answered as such
        if may_act(who.role, action, own):
            return None
        detail = f"{who.who} is a {who.role.name}: may not {action.replace('_', ' ')} it"
    elif who.role >= need:
        return None
    else:
        detail = f"{who.who} is a {who.role.name}: {kind} needs {need.name}"
    return {"type": "error", "command": kind, "status": 403, "detail": detail}


async def _receive(c: Components, ws: WebSocket, client: Client) -> None:
    """Read the client's messages; never awaits anything but the next one.

    Stop, pause and resume are realtime bytes, handled at once. Commands that
    wait for the board (jog, console lines) run in order in their own task,
    so a slow one never holds back an emergency stop sent after it.
    """
    waiting: asyncio.Queue[Command] = asyncio.Queue(WS_COMMANDS_WAITING)
    worker = asyncio.create_task(_board_commands(c, client, waiting))
    try:
        while True:
            message = await ws.receive()
            if message["type"] == "websocket.disconnect":
                return
            text = message.get("text")
            if text is None:
                text = (message.get("bytes") or b"").decode("utf-8", "replace")
            kind, body = parse_message(text)
            if kind == "estop":  # first thing, before anything else (never rate-limited);
                # answered at once, ahead of the events queued for this client
                await ws.send_text(json.dumps(_estop(c, body), separators=(",", ":")))
                _audit(c, client.identity, kind, body)
            elif not client.rate.take():
                await ws.close(code=1008, reason="too many messages")
                return
            elif body is None:
                c.clients.send(client, {"type": "error", "command": None, "detail": kind})
            elif (refused := refusal(c, client.identity, kind, body)) is not None:
                c.clients.send(client, refused)
                _audit(c, client.identity, kind, body, refused=403)
            else:
                _audit(c, client.identity, kind, body)
                if kind in AWAITING or (kind == "resume" and RESUME_WORDS & body.keys()):
                    try:
                        waiting.put_nowait((kind, body))
                    except asyncio.QueueFull:
                        c.clients.send(client, {"type": "error", "command": kind, "detail":
                                                "too many commands waiting for the board"})
                else:
                    c.clients.send(client, await _command(c, kind, body))
    finally:
        worker.cancel()


AUDITED = frozenset({"estop", "pause", "resume", "command", "job_action"})  # not jog: chatty
READ_ONLY = frozenset({"$", "$$", "$#", "$G", "$I", "$N", "?"})  # console lines that only ask


def _audit(c: Components, who: Identity, kind: Any, body: dict[str, Any] | None,
           **more: Any) -> None:  # fmt: skip
    """One audit entry for a message that changes something (never waits): not for a
    console line that only asks (a client repeating `$$` wrote a row each time)."""
    body = body or {}
    line = body.get("line")
    if kind == "command" and isinstance(line, str) and line.strip().upper() in READ_ONLY:
        return
    if kind in AUDITED:
        detail = {"action": body.get("action"), "plotter": body.get("plotter"),
                  "page": page_id(body.get("page")), "line": body.get("line"), **more}
        target = body.get("job") if isinstance(body.get("job"), str) else None
        c.access.audit(who, f"WS {kind}", target, {k: v for k, v in detail.items()
                                                   if v is not None})  # fmt: skip


def _estop(c: Components, body: dict[str, Any] | None) -> dict[str, Any]:
    """`{"type": "estop"}` stops the first plotter (or the named one), `"all": true` all;
    an unknown name stops nothing and is refused as REST refuses it (404, the plotters)."""
    body = body or {}
    origin = page_id(body.get("page"))
    if body.get("all") is True:
        c.queue.estop_all("WebSocket, all plotters", origin)
        return {"type": "ack", "command": "estop"}
    name = body.get("plotter")
    try:
        c.queue.estop(str(name) if name is not None else None, "WebSocket", origin)
    except Refused as exc:
        return {"type": "error", "command": "estop", "status": exc.status,
                "detail": exc.detail}  # fmt: skip
    return {"type": "ack", "command": "estop"}


async def _board_commands(c: Components, client: Client, waiting: asyncio.Queue[Command]) -> None:
    while True:
        kind, body = await waiting.get()
        try:
            answer = await _command(c, kind, body)
        except Exception as exc:  # a bug; the client's later commands must still run
            log.exception("WebSocket %s failed", kind)
            answer = {"type": "error", "command": kind, "detail": f"internal error: {exc}"}
        c.clients.send(client, answer)


async def _command(c: Components, kind: Any, message: dict[str, Any]) -> dict[str, Any]:
    name = message.get("plotter")
    try:
        target = name if isinstance(name, str) else None
        job = message.get("job")
        if kind == "job_action":
            action = message.get("action")
            if not isinstance(job, str) or not isinstance(action, str):
                raise Refused(422, "a job_action names its job and action")
            options = {k: v for k, v in message.items()
                       if k not in ("type", "job", "action", "plotter")}  # fmt: skip
            done = await c.actions.act(job, action, target, options or None)
            return {"type": "ack", "command": kind, "action": action, "job": done.public()}
        if kind == "pause":
            if isinstance(job, str):
                await c.actions.act(job, "hold")
            else:
                c.actions.hold_plotter(target)
        elif kind == "resume":  # with from/overlap/home: as POST /api/jobs/{id}/resume's body
            options = {k: v for k, v in message.items() if k in RESUME_WORDS}
            if isinstance(job, str):
                await c.actions.resume_legacy(job, target, options or None)
            elif options:
                raise Refused(422, "a resume from a point or after homing names its job")
            else:
                c.actions.continue_plotter(target)
        elif kind == "jog":
            body = JogBody(**{k: v for k, v in message.items() if k not in ("type", "plotter")})
            await c.queue.plotter(target).jog(body.dx, body.dy, body.feed)
        elif kind == "command":
            line = str(message.get("line", ""))
            try:
                responses = await c.queue.plotter(target).console(
                    line, message.get("confirm") is True)
            except Refused as exc:
                if exc.status != 428:
                    raise
                return {"type": "error", "command": kind, "detail": exc.detail, "confirm": True,
                        "line": line}  # fmt: skip
            return {"type": "ack", "command": kind, "responses": responses}
        else:
            return {"type": "error", "command": kind, "detail": f"unknown type {kind!r}"}
    except Refused as exc:
        answer = {"type": "error", "command": kind, "status": exc.status, "detail": exc.detail}
        if kind == "job_action":
            answer["action"] = message.get("action")
        return answer
    except ValidationError as exc:
        return {"type": "error", "command": kind, "detail": exc.errors(include_url=False)}
    return {"type": "ack", "command": kind}


def parse_message(text: str) -> tuple[Any, dict[str, Any] | None]:
    """(type, message), or (what is wrong, None). A message longer than any real
    one is refused unread: parsing megabytes would hold up the event loop."""
    if len(text) > WS_MESSAGE_MAX:
        return f"message longer than {WS_MESSAGE_MAX} characters", None
    try:
        message = json.loads(text)
    except ValueError:
        message = None
    if not isinstance(message, dict):
        return "send a JSON object with a type", None
    return message.get("type"), message
