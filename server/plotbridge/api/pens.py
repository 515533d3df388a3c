"""Pen library routes: the pens (CRUD), odometer reset, trying a pen's servo positions."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Path, Query
from fastapi.responses import Response

from plotbridge.api.deps import GUARD, Parts
from plotbridge.pens import Pen, PenPatch, PenSpec, TryBody
from plotbridge.pens.servo import try_pen

router = APIRouter(prefix="/api/pens", dependencies=GUARD, tags=["pens"])
PenRef = Annotated[str, Path(max_length=64, description="the pen's id or name")]
Target = Annotated[
    str | None, Query(max_length=64, description="the plotter (default: the first)")
]


@router.get("", response_model=list[Pen])
async def list_pens(c: Parts) -> list[dict[str, Any]]:
    return c.pens.list()


@router.post("", status_code=201, response_model=Pen)
async def add_pen(body: PenSpec, c: Parts) -> dict[str, Any]:
    return c.pens.public(await c.pens.create(body))


@router.get("/{pen}", response_model=Pen)
async def get_pen(pen: PenRef, c: Parts) -> dict[str, Any]:
    return c.pens.public(c.pens.get(pen))


@router.patch("/{pen}", response_model=Pen)
async def change_pen(pen: PenRef, body: PenPatch, c: Parts) -> dict[str, Any]:
    return c.pens.public(await c.pens.update(pen, body))


@router.delete("/{pen}", status_code=204)
async def delete_pen(pen: PenRef, c: Parts) -> Response:
    await c.pens.delete(pen)
    return Response(status_code=204)


@router.post("/{pen}/reset", response_model=Pen)
async def reset_odometer(pen: PenRef, c: Parts) -> dict[str, Any]:
    return c.pens.public(await c.pens.reset(pen))


@router.post("/{pen}/try")
async def try_positions(pen: PenRef, body: TryBody, c: Parts,
                        plotter: Target = None) -> dict[str, Any]:  # fmt: skip
    """Write the pen's $60/$61 to the plotter and move the servo there (409 while a job runs)."""
    unit = c.queue.plotter(plotter)
    return {"responses": await try_pen(unit, c.pens.get(pen), body.down),
            "machine": unit.machine()}  # fmt: skip
