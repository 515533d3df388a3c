"""Plotter routes: the list, the per-board verbs and the emergency stops.

The verbs exist twice: under `/api/plotters/{name}/machine` for a named
plotter, and under `/api/machine` for the first one (the single-plotter API).
"""

# No `from __future__ import annotations`: the routes made in `machine_routes` name
# a local type (the plotter they act on), which FastAPI must see evaluated.

import logging
from collections.abc import Callable
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Path, Request

from plotbridge.api.deps import GUARD, PAGE_HEADER, Parts, page_id
from plotbridge.models import CommandBody, JogBody, Machine, MotorsBody, PenBody, SettingsBody
from plotbridge.plotter.plotter import Plotter

log = logging.getLogger("plotbridge.api")

router = APIRouter(dependencies=GUARD)


def first_plotter(c: Parts) -> Plotter:
    return c.queue.first


def named_plotter(name: Annotated[str, Path(max_length=64)], c: Parts) -> Plotter:
    return c.queue.plotter(name)


@router.post("/api/plotters/{name}/machine/estop", status_code=202)
async def estop_named(name: Annotated[str, Path(max_length=64)], c: Parts,
                      request: Request) -> dict[str, Any]:  # fmt: skip
    """Stop one plotter at once; an unknown name stops nothing: 404 naming the plotters
    there are (the WebSocket's stop answers the same)."""
    plotter = c.queue.estop(name, "REST", page_id(request.headers.get(PAGE_HEADER)))
    return {"status": "stopped", "machine": plotter.machine()}


@router.get("/api/plotters")
async def plotters(c: Parts) -> list[dict[str, Any]]:
    return [plotter.describe() for plotter in c.queue.plotters.values()]


@router.post("/api/estop", status_code=202)
async def estop_all(c: Parts, request: Request) -> dict[str, Any]:
    # synchronous, before any await
    c.queue.estop_all("REST, all plotters", page_id(request.headers.get(PAGE_HEADER)))
    return {"status": "stopped", "plotters": list(c.queue.plotters)}


def machine_routes(prefix: str, pick: Callable[..., Plotter], estop: bool) -> APIRouter:
    """The per-board routes under `prefix`, for the plotter `pick` resolves (with its own
    `machine/estop` when `estop`)."""
    routes = APIRouter(prefix=prefix, dependencies=GUARD)
    Board = Annotated[Plotter, Depends(pick)]

    @routes.get("/machine", response_model=Machine)
    async def machine(plotter: Board) -> dict[str, Any]:
        return plotter.machine()

    if estop:
        @routes.post("/machine/estop", status_code=202)
        async def stop(plotter: Board, request: Request) -> dict[str, Any]:
            plotter.estop("REST", page_id(request.headers.get(PAGE_HEADER)))  # before awaits
            return {"status": "stopped", "machine": plotter.machine()}

    @routes.post("/machine/hold")
    async def hold(plotter: Board, c: Parts) -> dict[str, Any]:
        """Feed hold of the plotter's job, or of its machine: the pen lifts, position kept."""
        c.actions.hold_plotter(plotter.name)
        return {"machine": plotter.machine()}

    @routes.post("/machine/continue")
    async def go_on(plotter: Board, c: Parts) -> dict[str, Any]:
        """Cycle start after a hold: the pen lowers where it lifted, motion goes on."""
        c.actions.continue_plotter(plotter.name)
        return {"machine": plotter.machine()}

    @routes.post("/machine/unlock")
    async def unlock(plotter: Board) -> dict[str, Any]:
        log.info("%s: unlock ($X) requested", plotter.name)
        responses = await plotter.send("unlock", "$X")  # answered with the state it left
        return {"responses": responses, "machine": plotter.machine()}

    @routes.post("/machine/home")
    async def home(plotter: Board) -> dict[str, Any]:
        log.info("%s: homing ($H) requested", plotter.name)
        responses = await plotter.send("home", "$H", wait=120)
        return {"responses": responses, "machine": plotter.machine()}

    @routes.post("/machine/pen")
    async def pen(body: PenBody, plotter: Board) -> dict[str, Any]:
        return {"responses": await plotter.send("move the pen", "M3" if body.down else "M5")}

    @routes.post("/machine/jog")
    async def jog(body: JogBody, plotter: Board) -> dict[str, Any]:
        return {"responses": await plotter.jog(body.dx, body.dy, body.feed)}

    @routes.post("/machine/motors")
    async def motors(body: MotorsBody, plotter: Board) -> dict[str, Any]:
        line = "M17" if body.enabled else "M18"
        return {"responses": await plotter.send("switch the motors", line)}

    @routes.post("/machine/command")
    async def command(body: CommandBody, plotter: Board) -> dict[str, Any]:
        return {"responses": await plotter.console(body.line)}

    @routes.get("/machine/settings")
    async def settings(plotter: Board) -> dict[str, Any]:
        return {"settings": plotter.settings()}

    @routes.put("/machine/settings")
    async def put_settings(body: SettingsBody, plotter: Board) -> dict[str, Any]:
        responses = await plotter.write_settings(body.settings)
        return {"responses": responses, "settings": plotter.settings()}

    @routes.get("/sim/trace")
    async def sim_trace(plotter: Board) -> dict[str, Any]:
        return await plotter.trace()

    return routes


router.include_router(machine_routes("/api", first_plotter, estop=True))
router.include_router(machine_routes("/api/plotters/{name}", named_plotter, estop=False))
