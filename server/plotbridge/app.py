"""The FastAPI application: creates the components and mounts the routers."""

from __future__ import annotations

import logging
import socket
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from functools import partial

from fastapi import Depends, FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from fastapi.staticfiles import StaticFiles

from plotbridge import __version__
from plotbridge.api import jobs, notify, pens, people, plotters, session, ws
from plotbridge.api.deps import Components, authorize, error
from plotbridge.api.plotters import emergency_stop
from plotbridge.apidocs import mount_docs
from plotbridge.config import Config
from plotbridge.errors import Refused
from plotbridge.events import EventHub
from plotbridge.guard.middleware import Checks, Guard
from plotbridge.guard.stoplane import LANE
from plotbridge.jobs.actions import JobActions
from plotbridge.jobs.imports import Importer
from plotbridge.jobs.lifecycle import Lifecycle
from plotbridge.jobs.store import JobStore
from plotbridge.models import ERROR_RESPONSES
from plotbridge.mqtt.api import router as fleet_router
from plotbridge.mqtt.service import MqttService
from plotbridge.mqtt.verbs import Verbs
from plotbridge.notify import Webhooks
from plotbridge.pens import PenLibrary
from plotbridge.people import Access, PeopleStore
from plotbridge.people.migrate import take_old_sessions
from plotbridge.plotter.link import Link
from plotbridge.plotter.plotter import Plotter, WorkArea
from plotbridge.queue import JobQueue
from plotbridge.virtual import VirtualPlotter
from plotbridge.ws import Hub

log = logging.getLogger("plotbridge.app")

VALIDATION_ERRORS_SHOWN = 20


@dataclass
class Board:
    """What a plotter is made of: its name, its link, its simulator if virtual."""

    name: str
    link: Link
    virtual: VirtualPlotter | None = None
    work_area: WorkArea | None = None
    profile: str | None = None  # its board profile (firmware/src/boards/NAME.h)


def public_url(config: Config) -> str:
    """Where other machines reach this server's pages (the fleet view links there)."""
    host = socket.gethostname() if config.host in ("0.0.0.0", "::", "") else config.host
    return f"http://{host}:{config.port}/"


def create_app(config: Config, boards: list[Board], token: str) -> FastAPI:
    """Build the app around the boards' links (the first board is the default plotter)."""
    events = EventHub()
    clients = Hub()
    events.subscribe(clients.broadcast)
    webhooks = Webhooks(list(config.webhooks), config.data_dir, config.db_path,
                        allow_local=config.webhook_allow_local)  # fmt: skip
    events.subscribe(webhooks.publish)
    config.jobs_dir.mkdir(parents=True, exist_ok=True)
    config.tmp_dir.mkdir(exist_ok=True)
    for leftover in config.tmp_dir.glob("upload-*"):
        leftover.unlink(missing_ok=True)
    store = JobStore(config.db_path, first_plotter=boards[0].name)
    importer = Importer(config.jobs_dir, limits=config.import_limits)
    importer.clean()
    library = PenLibrary(config.db_path, events)
    people_store = PeopleStore(config.db_path)
    take_old_sessions(config.data_dir / "sessions.json", people_store)
    access = Access(people_store, token, config.token_file)
    lifecycle = Lifecycle(store, events)
    units = [Plotter(b.name, b.link, events, config.jobs_dir, lifecycle, virtual=b.virtual,
                     work_area=b.work_area, profile=b.profile,
                     home_on_connect=config.home_on_connect, after_job=config.after_job,
                     park=config.park,  # type: ignore[arg-type]
                     pens=library)
             for b in boards]  # fmt: skip
    queue = JobQueue(units, lifecycle, importer, events, auto_start=config.auto_start,
                     pens=library)  # fmt: skip
    queue.load()
    actions = JobActions(queue, lifecycle)
    mqtt = (MqttService(config.mqtt, Verbs(queue, actions, access), events, public_url(config),  # type: ignore[arg-type]
                        config.data_dir)
            if config.mqtt else None)  # fmt: skip

    @asynccontextmanager
    async def lifespan(_: FastAPI) -> AsyncIterator[None]:
        await webhooks.start()
        access.start()
        for plotter in units:
            plotter.start()
        if mqtt:
            mqtt.start()
        try:
            yield
        finally:
            if mqtt:
                await mqtt.close()
            for plotter in units:
                await plotter.stop()
            await webhooks.close()
            await access.close()
            importer.close()
            library.close()
            store.close()

    app = FastAPI(
        title="plotbridge", version=__version__, lifespan=lifespan, docs_url=None,
        redoc_url=None, openapi_url="/openapi.json", responses=ERROR_RESPONSES,
        dependencies=[Depends(authorize)],  # every route's role: plotbridge.access
    )  # fmt: skip
    mount_docs(app)  # /docs and /redoc from the package's own assets (offline)
    checks = Checks(access, config.allowed_hosts)
    app.add_middleware(Guard, checks=checks, upload_limit=config.upload_limit)
    LANE.bind(checks, partial(emergency_stop, queue))  # the real server's stop lane
    app.state.mqtt = mqtt
    app.state.components = Components(config, access, events, queue, actions, clients, library,
                                      webhooks)

    @app.exception_handler(Refused)
    async def refused(_: Request, exc: Refused) -> JSONResponse:
        return error(exc.status, exc.detail)

    @app.exception_handler(RequestValidationError)
    async def validation_error(_: Request, exc: RequestValidationError) -> JSONResponse:
        errors = [
            {
                "loc": [str(part)[:64] for part in err.get("loc", ())],
                "msg": err.get("msg"),
                "type": err.get("type"),
            }
            for err in exc.errors()[:VALIDATION_ERRORS_SHOWN]  # never the input: it may be huge
        ]
        return error(422, errors)

    @app.exception_handler(Exception)
    async def unexpected(_: Request, exc: Exception) -> JSONResponse:
        log.exception("unexpected error")  # a bug: bad input must never land here
        return error(500, f"internal error: {type(exc).__name__}: {exc}")

    for router in (session.router, plotters.router, jobs.router, pens.router, notify.router,
                   people.router, ws.router, fleet_router):
        app.include_router(router)
    if config.web_dir is not None and config.web_dir.is_dir():
        app.mount("/", StaticFiles(directory=config.web_dir, html=True), name="web")
    return app
