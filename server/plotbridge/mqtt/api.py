"""Fleet routes: the fleet as the broker shows it, and its stops (web/js/views/fleet.js)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request
from pydantic import BaseModel, Field

from plotbridge.api.deps import GUARD, Parts
from plotbridge.errors import Refused
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
