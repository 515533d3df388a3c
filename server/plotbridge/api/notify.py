"""Notification settings: the webhook URLs."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException

from plotbridge.api.deps import GUARD, Parts
from plotbridge.models import Webhooks, WebhooksBody

router = APIRouter(prefix="/api/settings", dependencies=GUARD)


@router.get("/webhooks", response_model=Webhooks)
async def get_webhooks(c: Parts) -> dict[str, Any]:
    return c.webhooks.view()


@router.put("/webhooks", response_model=Webhooks)
async def put_webhooks(body: WebhooksBody, c: Parts) -> dict[str, Any]:
    try:
        return await c.webhooks.replace(body.urls)
    except ValueError as exc:  # a URL reaching this machine (notify/targets.py)
        raise HTTPException(422, str(exc)) from None
