"""Job routes: upload, list, control, preview, patterns."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

from fastapi import APIRouter, Body, Query, Request
from fastapi import Path as PathParam
from fastapi.responses import FileResponse, JSONResponse, Response

from plotbridge.api.deps import GUARD, Parts, Who, upload_error
from plotbridge.errors import Refused
from plotbridge.jobs.model import AFTER_JOB, Job
from plotbridge.models import MoveBody, PatchJobBody, ResumeBody, upload_openapi
from plotbridge.mqtt.api import fleet_upload
from plotbridge.pens.model import parse_layer_pens
from plotbridge.people import Identity
from plotbridge.people.approval import needs_approval
from plotbridge.people.views import job_view, jobs_view
from plotbridge.upload import UploadRefused, parse_upload_fields, receive, refuse_unusable

router = APIRouter(prefix="/api", dependencies=GUARD)
Target = Annotated[
    str | None, Query(max_length=64, description="the plotter to run it on (default: any free)")
]


@router.get("/jobs", response_model=list[Job])
async def list_jobs(c: Parts, who: Who) -> JSONResponse:
    """As this person sees them (people/views.py: a submitter's own; `actions` theirs)."""
    assert who is not None
    return JSONResponse(jobs_view(who, c.queue.list()))


@router.post("/jobs", status_code=201, response_model=Job, openapi_extra=upload_openapi())
async def upload(request: Request, c: Parts, who: Who) -> Any:
    assert who is not None
    # the quota's room is reserved before a byte is written: the declared size, else the limit
    declared = request.headers.get("content-length", "")
    size = int(declared) if declared.isdigit() else c.config.upload_limit
    async with c.queue.importer.reserve(min(size, c.config.upload_limit)):
        return await _upload(request, c, who)


async def _upload(request: Request, c: Parts, who: Identity) -> Any:
    config = c.config
    try:
        path, filename, fields = await receive(request, config.tmp_dir, config.upload_limit)
    except UploadRefused as exc:
        return upload_error(exc.status, exc.message)
    try:
        params = {**dict(request.query_params), **fields}
        try:
            options, placement, start = parse_upload_fields(params)
        except ValueError as exc:
            return upload_error(422, str(exc))
        try:
            pens = parse_layer_pens(params["pens"]) if params.get("pens") else None
        except ValueError as exc:
            return upload_error(422, str(exc))
        after = params.get("after") or None
        if after is not None and after not in AFTER_JOB:
            return upload_error(422, f"after: one of {', '.join(AFTER_JOB)}, got {after!r}")
        pattern = params.get("pattern")
        if pattern:
            kind, source, filename = "pattern", pattern, pattern
        elif path is None:
            return upload_error(422, "no file: send multipart field 'file' or a raw body")
        else:
            refuse_unusable(path)
            kind, source = "file", path
            filename = filename or params.get("filename") or params.get("name") or "upload"
        name = (params.get("name") or Path(filename).name or "untitled")[:200]
        approval = ({"start": start, "decision": None}
                    if needs_approval(c.access.approval_mode, who.role) else None)  # fmt: skip
        options["name"] = name
        job = await c.queue.create(kind=kind, source=source, filename=filename, name=name,
                                   options=options, placement=placement,
                                   target=params.get("plotter") or None,
                                   after=after, pens=pens, owner=who.who,
                                   approval=approval)  # fmt: skip
    except UploadRefused as exc:
        return upload_error(exc.status, exc.message)
    finally:
        if path is not None:
            path.unlink(missing_ok=True)
    request.state.audit = {"job": job.id, "name": name, "awaiting_approval": bool(approval)}
    # MQTT fleet (`fleet=true`): only a job that waits for no approval leaves this bridge
    if not approval and (offered := await fleet_upload(request, params, job)) is not None:
        return offered
    answer = job.public()
    if start and job.state == "queued":
        try:
            answer = (await c.actions.act(job.id, "start")).public()
        except Refused as exc:  # the upload stands; say why it did not start
            answer["start_error"] = exc.detail
    return JSONResponse(answer, status_code=201)


@router.get("/jobs/{job_id}", response_model=Job)
async def get_job(job_id: str, c: Parts, who: Who) -> JSONResponse:
    assert who is not None
    return JSONResponse(job_view(who, c.queue.get(job_id).public()))


@router.patch("/jobs/{job_id}", response_model=Job)
async def patch_job(job_id: str, body: PatchJobBody,
                    c: Parts) -> dict[str, Any]:  # fmt: skip
    # only the fields sent: the others keep what the job has (never reset to defaults)
    placement = body.placement.model_dump(exclude_unset=True) if body.placement else None
    job = c.queue.get(job_id)
    if body.name is not None or placement is not None:
        job = await c.queue.reimport(job_id, body.name, placement)
    if body.pens is not None:
        job = c.queue.set_pens(job_id, body.pens)
    return job.public()


@router.delete("/jobs/{job_id}", status_code=204)
async def delete_job(job_id: str, c: Parts) -> Response:
    await c.actions.act(job_id, "delete")
    return Response(status_code=204)


@router.post("/jobs/{job_id}/move", response_model=list[Job])
async def move_job(job_id: str, body: MoveBody,
                   c: Parts) -> list[dict[str, Any]]:  # fmt: skip
    await c.actions.act(job_id, "move", body=body.model_dump())
    return c.queue.list()


@router.post("/jobs/{job_id}/pause", response_model=Job)
async def pause_job(job_id: str, c: Parts) -> dict[str, Any]:
    """The old name of `hold`."""
    return (await c.actions.act(job_id, "hold")).public()


@router.post("/jobs/{job_id}/resume", response_model=Job)
async def resume_job(job_id: str, c: Parts, plotter: Target = None,
                     body: ResumeBody | None = None) -> dict[str, Any]:  # fmt: skip
    """`continue` a held job or a pen change, or `resume` a stopped or interrupted one where
    it stopped; with a body, `resume_from` a point (`from`, `overlap`) and/or
    `home_then_resume` (`home`)."""
    sent = body.model_dump(by_alias=True, exclude_unset=True) if body is not None else None
    return (await c.actions.resume_legacy(job_id, plotter, sent)).public()


@router.post("/jobs/{job_id}/{action}", response_model=Job)
async def job_action(job_id: str, action: Annotated[str, PathParam(max_length=32)], c: Parts,
                     plotter: Target = None,
                     body: Annotated[dict[str, Any] | None, Body()] = None,
                     ) -> dict[str, Any]:  # fmt: skip
    """One of the job's `actions` (docs/INTERNALS.md, "The job lifecycle"): start, hold,
    continue, stop, resume, home_then_resume, resume_from, restart, cancel, frame. The body
    is the action's options (start, restart: StartBody; resume_from: ResumeBody).
    An action the job's state does not allow answers 409 with its state and actions."""
    if action in ("delete", "edit", "move"):
        raise Refused(405, f"{action}: use {ROUTED[action]}")
    return (await c.actions.act(job_id, action, plotter, body)).public()


ROUTED = {"delete": "DELETE /api/jobs/{id}", "edit": "PATCH /api/jobs/{id}",
          "move": "POST /api/jobs/{id}/move with {\"position\"}"}


@router.get("/jobs/{job_id}/preview")
async def preview(job_id: str, c: Parts) -> Response:
    path = c.queue.preview_path(job_id)
    if not path.exists():
        raise Refused(404, f"job {job_id} has no preview")
    # A placement change rewrites the file, so its ETag (mtime, size) changes; no-cache
    # makes the browser ask every time instead of drawing a stale preview from its cache.
    return FileResponse(path, media_type="application/json",
                        headers={"Cache-Control": "no-cache"})  # fmt: skip


@router.get("/patterns")
async def patterns(c: Parts) -> dict[str, Any]:
    known = await c.queue.importer.patterns()
    return {"patterns": [{"name": k, "description": v} for k, v in known.items()]}
