"""The FastAPI application: REST, WebSocket, login and the static web UI."""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from fastapi import Depends, FastAPI, Request, WebSocket
from fastapi.exceptions import HTTPException, RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, RedirectResponse, Response
from fastapi.staticfiles import StaticFiles
from pydantic import ValidationError

from plotbridge import __version__
from plotbridge.auth import COOKIE, SESSION_TTL, Auth
from plotbridge.config import Config
from plotbridge.guard.middleware import Guard
from plotbridge.jobs import JobError, JobManager, public
from plotbridge.models import (
    ERROR_RESPONSES,
    CommandBody,
    Job,
    JogBody,
    LoginBody,
    Machine,
    MotorsBody,
    MoveBody,
    PatchJobBody,
    PenBody,
    Placement,
    SettingsBody,
    upload_openapi,
)
from plotbridge.store import JobStore
from plotbridge.upload import UploadRefused, receive, refuse_unusable
from plotbridge.ws import Hub

log = logging.getLogger("plotbridge.app")

WS_MESSAGE_MAX = 4096  # characters; the longest real message (a console line) is ~200
WS_COMMANDS_WAITING = 16  # per WebSocket client: jog and console lines not yet answered
VALIDATION_ERRORS_SHOWN = 20  # never the input itself: it may be megabytes
TRUE = ("1", "true", "yes", "on")
FALSE = ("0", "false", "no", "off", "")


def _error(status: int, detail: Any) -> JSONResponse:
    return JSONResponse({"detail": detail}, status_code=status)


def _upload_error(status: int, message: str) -> JSONResponse:
    return _error(status, {"errors": [{"line": None, "message": message}]})


def create_app(config: Config, link: Any, token: str, virtual: Any = None) -> FastAPI:
    """Build the app around a `Link` (and the `VirtualPlotter` in virtual mode)."""
    auth = Auth(token, config.token_file)
    hub = Hub()
    config.jobs_dir.mkdir(parents=True, exist_ok=True)
    (config.data_dir / "tmp").mkdir(exist_ok=True)
    store = JobStore(config.db_path)
    manager = JobManager(config, link, hub, store)
    manager.load()

    @asynccontextmanager
    async def lifespan(_: FastAPI) -> AsyncIterator[None]:
        manager.start()
        link_task = asyncio.create_task(link.run(), name="link")
        try:
            yield
        finally:
            await manager.stop()
            link_task.cancel()
            with contextlib.suppress(BaseException):
                await link_task
            store.close()

    app = FastAPI(
        title="plotbridge", version=__version__, lifespan=lifespan, docs_url="/docs",
        redoc_url=None, openapi_url="/openapi.json", responses=ERROR_RESPONSES,
    )  # fmt: skip
    app.add_middleware(
        Guard, auth=auth, upload_limit=config.upload_limit, allowed_hosts=config.allowed_hosts
    )
    app.state.manager = manager
    app.state.hub = hub
    app.state.link = link
    app.state.virtual = virtual

    @app.exception_handler(JobError)
    async def job_error(_: Request, exc: JobError) -> JSONResponse:
        return _error(exc.status, exc.detail)

    @app.exception_handler(RequestValidationError)
    async def validation_error(_: Request, exc: RequestValidationError) -> JSONResponse:
        errors = [
            {
                "loc": [str(part)[:64] for part in err.get("loc", ())],
                "msg": err.get("msg"),
                "type": err.get("type"),
            }
            for err in exc.errors()[:VALIDATION_ERRORS_SHOWN]
        ]
        return _error(422, errors)

    @app.exception_handler(Exception)
    async def unexpected(_: Request, exc: Exception) -> JSONResponse:
        log.exception("unexpected error")  # a bug: bad input must never land here
        return _error(500, f"internal error: {type(exc).__name__}: {exc}")

    async def authenticated(request: Request) -> None:  # async: no thread-pool hop
        if auth.check_header(request.headers.get("authorization")):
            return
        if auth.check_session(request.cookies.get(COOKIE)):
            return
        raise HTTPException(
            401, "missing or wrong token: send 'Authorization: Bearer TOKEN' or log in",
            headers={"WWW-Authenticate": "Bearer"},
        )  # fmt: skip

    guard = [Depends(authenticated)]

    def set_cookie(response: Response) -> None:
        response.set_cookie(
            COOKIE, auth.new_session(), httponly=True, samesite="strict", path="/",
            max_age=int(SESSION_TTL),
        )  # fmt: skip

    # ---- health, login, server ------------------------------------------------

    @app.get("/api/health")
    async def health() -> dict[str, str]:
        return {"status": "ok"}

    @app.post("/api/login", status_code=204)
    async def login(body: LoginBody) -> Response:
        if not auth.check_token(body.token):
            raise HTTPException(401, "wrong token")
        response = Response(status_code=204)
        set_cookie(response)
        return response

    @app.get("/login")
    async def login_link(token: str = "") -> Response:
        if not auth.check_token(token):
            return _error(401, "wrong or missing token in the login link")
        response = RedirectResponse("/", status_code=303)
        set_cookie(response)
        return response

    @app.post("/api/logout", status_code=204)
    async def logout(request: Request) -> Response:
        auth.end_session(request.cookies.get(COOKIE))
        response = Response(status_code=204)
        response.delete_cookie(COOKIE, path="/")
        return response

    @app.get("/api/server", dependencies=guard)
    async def server_info() -> dict[str, Any]:
        return {
            "version": __version__,
            "virtual": config.virtual,
            "serial": config.serial,
            "data_dir": str(config.data_dir),
            "upload_limit": config.upload_limit,
            "auto_start": config.auto_start,
        }

    # ---- machine ------------------------------------------------------------------

    @app.get("/api/machine", dependencies=guard, response_model=Machine)
    async def machine() -> dict[str, Any]:
        return manager.machine()

    @app.post("/api/machine/estop", dependencies=guard, status_code=202)
    async def estop_now() -> dict[str, Any]:
        manager.estop("REST")  # synchronous, before any await
        return {"status": "stopped", "machine": manager.machine()}

    def idle_machine(action: str) -> None:
        if manager.active is not None:
            raise JobError(409, f"cannot {action} while job {manager.active} is running")

    async def board(line: str, wait: float = 10.0) -> list[str]:
        from plotbridge.link import CommandError, LinkDown

        try:
            return await link.command(line, timeout=wait)
        except CommandError as exc:  # error:9 is GRBL's "not in this state" (Alarm, Jog)
            status = 409 if exc.code == 9 else 422
            raise JobError(status, f"the board refused {line!r}: {exc}") from exc
        except LinkDown as exc:
            raise JobError(409, "the plotter is not connected") from exc
        except TimeoutError as exc:
            raise JobError(409, f"the board did not answer {line!r} within {wait:g} s") from exc

    async def idle_board(action: str, line: str, wait: float = 10.0) -> dict[str, Any]:
        """One line to the board while no job runs; the answer of the machine endpoints."""
        idle_machine(action)
        return {"responses": await board(line, wait)}

    @app.post("/api/machine/unlock", dependencies=guard)
    async def unlock() -> dict[str, Any]:
        log.info("unlock ($X) requested")
        return await idle_board("unlock", "$X")

    @app.post("/api/machine/home", dependencies=guard)
    async def home() -> dict[str, Any]:
        log.info("homing ($H) requested")
        answer = await idle_board("home", "$H", wait=120)
        log.info("homing done")
        return answer

    @app.post("/api/machine/pen", dependencies=guard)
    async def pen(body: PenBody) -> dict[str, Any]:
        return await idle_board("move the pen", "M3" if body.down else "M5")

    @app.post("/api/machine/jog", dependencies=guard)
    async def jog(body: JogBody) -> dict[str, Any]:
        return {"responses": await do_jog(body)}

    async def do_jog(body: JogBody) -> list[str]:
        idle_machine("jog")
        state = manager.machine()["state"]
        if state not in ("Idle", "Jog"):
            raise JobError(409, f"cannot jog while the machine is {state}")
        return await board(f"$J=G91 G21 X{body.dx:.3f} Y{body.dy:.3f} F{body.feed:.0f}")

    @app.post("/api/machine/motors", dependencies=guard)
    async def motors(body: MotorsBody) -> dict[str, Any]:
        return await idle_board("switch the motors", "M17" if body.enabled else "M18")

    @app.post("/api/machine/command", dependencies=guard)
    async def command(body: CommandBody) -> dict[str, Any]:
        return {"responses": await do_command(body.line)}

    async def do_command(line: str) -> list[str]:
        idle_machine("send commands")
        line = line.strip()
        if not line or any(ch in line for ch in "?!~\x18\r\n") or not line.isprintable():
            raise JobError(422, "one printable G-code or $ line, without realtime characters")
        return [*await board(line, wait=30), "ok"]  # the link keeps the ok to itself

    @app.get("/api/machine/settings", dependencies=guard)
    async def settings() -> dict[str, Any]:
        return {"settings": settings_view(getattr(link, "settings", {}) or {})}

    @app.put("/api/machine/settings", dependencies=guard)
    async def put_settings(body: SettingsBody) -> dict[str, Any]:
        idle_machine("change settings")
        responses = []
        for number, value in body.settings.items():
            text = f"{value:g}" if value != int(value) else str(int(value))
            responses += await board(f"${number}={text}")  # the link notes accepted values
        return {"responses": responses, "settings": settings_view(link.settings or {})}

    # ---- jobs --------------------------------------------------------------------------

    @app.get("/api/jobs", dependencies=guard, response_model=list[Job])
    async def list_jobs() -> list[dict[str, Any]]:
        return manager.list()

    @app.post("/api/jobs", dependencies=guard, status_code=201, response_model=Job,
              openapi_extra=upload_openapi())  # fmt: skip
    async def upload(request: Request) -> Any:
        tmp_dir = config.data_dir / "tmp"
        try:
            path, filename, fields = await receive(request, tmp_dir, config.upload_limit)
        except UploadRefused as exc:
            return _upload_error(exc.status, exc.message)
        try:
            params = {**dict(request.query_params), **fields}
            try:
                options, placement, start = parse_upload_fields(params)
            except ValueError as exc:
                return _upload_error(422, str(exc))
            pattern = params.get("pattern")
            if pattern:
                kind, source, filename = "pattern", pattern, pattern
            elif path is None:
                return _upload_error(422, "no file: send multipart field 'file' or a raw body")
            else:
                refuse_unusable(path)
                kind, source = "file", path
                filename = filename or params.get("filename") or params.get("name") or "upload"
            name = (params.get("name") or Path(filename).name or "untitled")[:200]
            options["name"] = name
            job = await manager.create(kind=kind, source=source, filename=filename, name=name,
                                       options=options, placement=placement)  # fmt: skip
        except UploadRefused as exc:
            return _upload_error(exc.status, exc.message)
        finally:
            if path is not None:
                path.unlink(missing_ok=True)
        answer = public(job)
        if start and job["state"] == "queued":
            try:
                answer = public(manager.start_job(job["id"]))
            except JobError as exc:  # the upload stands; say why it did not start
                answer["start_error"] = exc.detail
        return JSONResponse(answer, status_code=201)

    @app.get("/api/jobs/{job_id}", dependencies=guard, response_model=Job)
    async def get_job(job_id: str) -> dict[str, Any]:
        return public(manager.get(job_id))

    @app.patch("/api/jobs/{job_id}", dependencies=guard, response_model=Job)
    async def patch_job(job_id: str, body: PatchJobBody) -> dict[str, Any]:
        placement = body.placement.model_dump() if body.placement else None
        return public(await manager.reimport(job_id, body.name, placement))

    @app.delete("/api/jobs/{job_id}", dependencies=guard, status_code=204)
    async def delete_job(job_id: str) -> Response:
        await manager.delete(job_id)
        return Response(status_code=204)

    @app.post("/api/jobs/{job_id}/start", dependencies=guard, response_model=Job)
    async def start_job(job_id: str) -> dict[str, Any]:
        return public(manager.start_job(job_id))

    @app.post("/api/jobs/{job_id}/pause", dependencies=guard, response_model=Job)
    async def pause_job(job_id: str) -> dict[str, Any]:
        return public(manager.pause(job_id))

    @app.post("/api/jobs/{job_id}/resume", dependencies=guard, response_model=Job)
    async def resume_job(job_id: str) -> dict[str, Any]:
        return public(manager.resume(job_id))

    @app.post("/api/jobs/{job_id}/cancel", dependencies=guard, response_model=Job)
    async def cancel_job(job_id: str) -> dict[str, Any]:
        return public(await manager.cancel(job_id))

    @app.post("/api/jobs/{job_id}/move", dependencies=guard, response_model=list[Job])
    async def move_job(job_id: str, body: MoveBody) -> list[dict[str, Any]]:
        return manager.move(job_id, body.position)

    @app.get("/api/jobs/{job_id}/preview", dependencies=guard)
    async def preview(job_id: str) -> Response:
        path = manager.preview_path(job_id)
        if not path.exists():
            raise JobError(404, f"job {job_id} has no preview")
        return FileResponse(path, media_type="application/json")

    @app.get("/api/patterns", dependencies=guard)
    async def patterns() -> dict[str, Any]:
        known = await manager.patterns()
        return {"patterns": [{"name": k, "description": v} for k, v in known.items()]}

    @app.get("/api/sim/trace", dependencies=guard)
    async def sim_trace() -> dict[str, Any]:
        if virtual is None:
            raise JobError(404, "no virtual plotter: the server drives a real board (--serial)")
        trace = await asyncio.to_thread(virtual.trace)
        strokes = [[[p[0], p[1]] for p in stroke] for stroke in trace.get("strokes", [])]
        return {**trace, "strokes": strokes}

    # ---- WebSocket ------------------------------------------------------------------

    @app.websocket("/api/ws")
    async def websocket(ws: WebSocket) -> None:
        await ws.accept()  # the guard has checked the session or token and the Origin
        client = hub.add(ws)
        for message in manager.snapshot_messages():
            hub.send(client, message)
        client.task = asyncio.create_task(client.pump())
        receiver = asyncio.create_task(ws_receive(ws, client))
        try:
            await asyncio.wait({client.task, receiver}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            hub.remove(client)
            for task in (client.task, receiver):
                task.cancel()
            with contextlib.suppress(Exception):
                await ws.close()

    async def ws_receive(ws: WebSocket, client: Any) -> None:
        """Read the client's messages; never awaits anything but the next one.

        Stop, pause and resume are realtime bytes, handled at once. Commands that
        wait for the board (jog, console lines) run in order in their own task,
        so a slow one never holds back an emergency stop sent after it.
        """
        waiting: asyncio.Queue[tuple[str, dict[str, Any]]] = asyncio.Queue(WS_COMMANDS_WAITING)
        worker = asyncio.create_task(ws_board_commands(client, waiting))
        try:
            while True:
                message = await ws.receive()
                if message["type"] == "websocket.disconnect":
                    return
                text = message.get("text")
                if text is None:
                    text = (message.get("bytes") or b"").decode("utf-8", "replace")
                kind, body = _parse_message(text)
                if kind == "estop":  # first thing, before anything else (never rate-limited)
                    manager.estop("WebSocket")
                    hub.send(client, {"type": "ack", "command": "estop"})
                elif not client.rate.take():
                    await ws.close(code=1008, reason="too many messages")
                    return
                elif body is None:
                    hub.send(client, {"type": "error", "command": None, "detail": kind})
                elif kind in ("jog", "command"):
                    try:
                        waiting.put_nowait((kind, body))
                    except asyncio.QueueFull:
                        hub.send(client, {"type": "error", "command": kind, "detail":
                                          "too many commands waiting for the board"})
                else:
                    hub.send(client, await ws_command(kind, body))
        finally:
            worker.cancel()

    async def ws_board_commands(
        client: Any, waiting: asyncio.Queue[tuple[str, dict[str, Any]]]
    ) -> None:
        while True:
            kind, body = await waiting.get()
            try:
                answer = await ws_command(kind, body)
            except Exception as exc:  # a bug; the client's later commands must still run
                log.exception("WebSocket %s failed", kind)
                answer = {"type": "error", "command": kind, "detail": f"internal error: {exc}"}
            hub.send(client, answer)

    async def ws_command(kind: Any, message: dict[str, Any]) -> dict[str, Any]:
        try:
            if kind == "pause":
                manager.pause(message.get("job"))
            elif kind == "resume":
                manager.resume(message.get("job"))
            elif kind == "jog":
                await do_jog(JogBody(**{k: v for k, v in message.items() if k != "type"}))
            elif kind == "command":
                responses = await do_command(str(message.get("line", "")))
                return {"type": "ack", "command": kind, "responses": responses}
            else:
                return {"type": "error", "command": kind, "detail": f"unknown type {kind!r}"}
        except JobError as exc:
            return {"type": "error", "command": kind, "detail": exc.detail}
        except ValidationError as exc:
            return {"type": "error", "command": kind, "detail": exc.errors(include_url=False)}
        return {"type": "ack", "command": kind}

    # ---- static UI ----------------------------------------------------------------------

    if config.web_dir is not None and config.web_dir.is_dir():
        app.mount("/", StaticFiles(directory=config.web_dir, html=True), name="web")

    return app


def _parse_message(text: str) -> tuple[Any, dict[str, Any] | None]:
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


def settings_view(values: dict[int, float]) -> list[dict[str, Any]]:
    """Settings with their names, units and descriptions where the link knows them."""
    from plotbridge.settings_meta import SETTINGS as table

    view = []
    for number in sorted(values, key=int):
        meta = table.get(int(number))
        entry = {"id": int(number), "value": values[number]}
        for key in ("name", "unit", "description"):
            entry[key] = getattr(meta, key, None)
        view.append(entry)
    return view


def parse_upload_fields(params: dict[str, str]) -> tuple[dict[str, Any], dict[str, Any], bool]:
    """Import options, placement and `start` from form fields or query parameters."""

    def flag(key: str) -> bool | None:
        if key not in params:
            return None
        value = params[key].strip().lower()
        if value in TRUE:
            return True
        if value in FALSE:
            return False
        raise ValueError(f"{key}: expected true or false, got {params[key]!r}")

    raw = {k: params[k] for k in Placement.model_fields if k in params}
    if "fit" in raw:
        raw["fit"] = flag("fit")
    try:
        placement = Placement(**raw)
    except ValidationError as exc:
        first = exc.errors(include_url=False)[0]
        field = ".".join(str(part) for part in first.get("loc", ()))
        raise ValueError(f"{field}: {first.get('msg')}") from exc
    options: dict[str, Any] = placement.model_dump()
    optimize = flag("optimize")
    if optimize is not None:
        options["optimize"] = optimize
    if params.get("layers"):
        options["layers"] = [part.strip() for part in params["layers"].split(",") if part.strip()]
    placement_public = {k: v for k, v in options.items() if k in Placement.model_fields}
    return options, placement_public, bool(flag("start"))
