"""People, API keys, the audit log and the approval setting (admins; the rules are in
plotbridge.access). Every change here is audited and takes effect at once: a removed
person's or key's WebSockets close."""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Annotated, Any, Literal

from fastapi import APIRouter, HTTPException, Path, Query, Request
from fastapi.responses import Response, StreamingResponse
from pydantic import BaseModel, ConfigDict, Field

from plotbridge.access import ROLES, Role
from plotbridge.api.deps import Parts, Who
from plotbridge.people.approval import MODES
from plotbridge.people.store import TOKEN_OWNER

router = APIRouter(prefix="/api")
Name = Annotated[str, Path(max_length=64)]


class NewBody(BaseModel):
    model_config = ConfigDict(extra="forbid")
    name: str = Field(max_length=64)
    role: Literal["viewer", "submitter", "operator", "admin"]


class ApprovalBody(BaseModel):
    model_config = ConfigDict(extra="forbid")
    mode: Literal["submitters", "all", "none"] = Field(
        description="whose uploads wait for approval: submitters' (default), all, none")


def login_url(request: Request, code: str) -> str:
    return f"{str(request.base_url).rstrip('/')}/login.html#{code}"


async def _made(c: Parts, fn: Any, *args: Any) -> Any:
    try:
        return await c.access.change(fn, *args)
    except ValueError as exc:
        raise HTTPException(422, str(exc)) from None


@router.get("/people")
async def list_people(c: Parts) -> list[dict[str, Any]]:
    return await c.access.read(c.access.store.people)


@router.post("/people", status_code=201)
async def add_person(body: NewBody, c: Parts, who: Who, request: Request) -> dict[str, Any]:
    """A person and their one-time login link (the link becomes a session once used)."""
    await _made(c, c.access.store.add_person, body.name, Role.parse(body.role))
    code = await _made(c, c.access.store.new_link, body.name, "person")
    c.access.audit(who, "person_added", body.name, {"role": body.role})
    return {"name": body.name, "role": body.role, "link": login_url(request, code)}


async def _removed(c: Parts, who: Who, remove: Any, name: str, what: str) -> Response:
    """`remove(name)` in the store (404 when there was none), audited as `what_removed`."""
    if not await _made(c, remove, name):
        raise HTTPException(404, f"no {what} named {name!r}")
    c.access.audit(who, f"{what}_removed", name)
    return Response(status_code=204)


@router.delete("/people/{name}", status_code=204)
async def remove_person(name: Name, c: Parts, who: Who) -> Response:
    return await _removed(c, who, c.access.store.remove_person, name, "person")


@router.post("/people/{name}/reset")
async def reset_person(name: Name, c: Parts, who: Who, request: Request) -> dict[str, Any]:
    """Ends the person's sessions; a new one-time link (earlier ones are void)."""
    if name.lower() == TOKEN_OWNER or await c.access.read(c.access.store.person_role, name) is None:
        raise HTTPException(404, f"no person named {name!r}")
    await _made(c, c.access.store.end_sessions, name, "person")
    code = await _made(c, c.access.store.new_link, name, "person")
    c.access.audit(who, "person_reset", name)
    return {"name": name, "link": login_url(request, code)}


@router.get("/keys")
async def list_keys(c: Parts) -> list[dict[str, Any]]:
    return await c.access.read(c.access.store.keys)


@router.post("/keys", status_code=201)
async def add_key(body: NewBody, c: Parts, who: Who) -> dict[str, Any]:
    """A new API key: shown in this answer only (the server keeps its digest)."""
    key = await _made(c, c.access.store.add_key, body.name, Role.parse(body.role))
    c.access.audit(who, "key_added", body.name, {"role": body.role})
    return {"name": body.name, "role": body.role, "key": key, "server": c.access.server_id}


@router.delete("/keys/{name}", status_code=204)
async def remove_key(name: Name, c: Parts, who: Who) -> Response:
    return await _removed(c, who, c.access.store.remove_key, name, "key")


@router.get("/audit")
async def audit(
    c: Parts,
    limit: Annotated[int, Query(ge=1, le=1000)] = 100,
    before: Annotated[int | None, Query(ge=1, description="entries older than this id")] = None,
) -> list[dict[str, Any]]:
    """Who did what, newest first."""
    return await c.access.read(c.access.store.audit, limit, before)


@router.get("/audit/export", response_class=StreamingResponse, responses={
    200: {"description": "one JSON object per line", "content": {"application/x-ndjson": {}}}})
async def audit_export(c: Parts) -> StreamingResponse:
    """The whole log as JSON lines, oldest first."""
    entries = await c.access.read(lambda: list(c.access.store.audit_all()))

    def lines() -> Iterator[str]:
        for entry in entries:
            yield json.dumps(entry) + "\n"

    return StreamingResponse(lines(), media_type="application/x-ndjson", headers={
        "content-disposition": 'attachment; filename="plotbridge-audit.jsonl"'})


@router.get("/settings/approval")
async def get_approval(c: Parts) -> dict[str, Any]:
    return {"mode": c.access.approval_mode, "modes": list(MODES), "roles": list(ROLES)}


@router.put("/settings/approval")
async def put_approval(body: ApprovalBody, c: Parts, who: Who) -> dict[str, Any]:
    await c.access.change(c.access.store.set_setting, "approval", body.mode)
    c.access.audit(who, "setting", "approval", {"mode": body.mode})
    return {"mode": body.mode, "modes": list(MODES), "roles": list(ROLES)}
