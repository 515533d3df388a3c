"""Fleet routes: the fleet as the broker shows it, and its stops (web/js/views/fleet.js)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse
from pydantic import BaseModel, Field

from plotbridge.api.deps import GUARD, Parts, upload_error
from plotbridge.errors import Refused
from plotbridge.jobs.model import Job
from plotbridge.mqtt.service import MqttService

router = APIRouter(prefix="/api/fleet", dependencies=GUARD)
NAME = r"^[A-Za-z0-9_-]{1,64}$"


class StopBody(BaseModel):
    bridge: str = Field(pattern=NAME)
    plotter: str = Field(pattern=NAME)


def _service(request: Request) -> MqttService | None:
    return getattr(request.app.state, "mqtt", None)


@router.get("")
async def fleet(request: Request) -> dict[str, Any]:
    service = _service(request)
    if service is None:
        return {"enabled": False, "bridges": []}
    return service.describe()


@router.post("/stop", status_code=202)
async def stop(body: StopBody, request: Request) -> dict[str, Any]:
    """STOP one plotter of the fleet (another bridge's through the broker)."""
    service = _service(request)
    if service is None:
        raise Refused(409, "MQTT is off: this bridge sees no fleet (start with --mqtt URL)")
    sent = await service.stop(body.bridge, body.plotter)
    if not sent:
        raise Refused(503, f"the broker did not take the STOP for {body.bridge}/{body.plotter}"
                           ": use that bridge's own page or its plotter's stop button")
    return {"status": "stopped", "bridge": body.bridge, "plotter": body.plotter}


@router.post("/estop", status_code=202)
async def stop_everything(request: Request, c: Parts) -> dict[str, Any]:
    """STOP EVERYTHING: this bridge's plotters at once, every other bridge's through the
    broker (`fleet`: whether the broker took it)."""
    service = _service(request)
    if service is None:
        c.queue.estop_all("REST, STOP EVERYTHING (no fleet: MQTT is off)")
        return {"status": "stopped", "fleet": False}
    return {"status": "stopped", "fleet": await service.stop_everything()}


async def fleet_upload(request: Request, params: dict[str, str], job: Job) -> JSONResponse | None:
    """An upload's `fleet` field: true hands the imported job to the fleet's queue (the
    answer says so); absent or false: None, the upload stays a local job."""
    flag = params.get("fleet", "").strip().lower()
    if flag in ("", "0", "false", "no", "off"):
        return None
    c = request.app.state.components
    if flag not in ("1", "true", "yes", "on"):
        await c.queue.delete(job.id)
        return upload_error(422, f"fleet: expected true or false, got {params['fleet']!r}")
    service = _service(request)
    if service is None:
        await c.queue.delete(job.id)
        return upload_error(409, "fleet=true needs MQTT: start the server with --mqtt URL")
    return JSONResponse(await service.origin.offer(job.public()), status_code=201)
