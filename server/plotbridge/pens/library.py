"""The pen library: pens by id, their odometers, and which pen draws which layer.

Kept in memory (the truth while running) and mirrored to `PenStore`; every change is
published as a `pens` event. Odometers grow with each acknowledged pen-down line
(`drawn`) and reach the disk at most once per `FLUSH_S` (one transaction for all
pens), and at once when a job ends or the server stops.
"""

from __future__ import annotations

import asyncio
import logging
import sqlite3
from pathlib import Path
from typing import TYPE_CHECKING, Any

from plotbridge.errors import Refused
from plotbridge.events import EventHub
from plotbridge.pens.model import Pen, PenPatch, PenSpec
from plotbridge.pens.store import PenStore

if TYPE_CHECKING:
    from plotbridge.jobs.model import Layer

log = logging.getLogger("plotbridge.pens")

FLUSH_S = 1.0  # s at most between an odometer change and its write


class PenLibrary:
    def __init__(self, path: Path, events: EventHub) -> None:
        self.store = PenStore(path)
        self.events = events
        self.pens: dict[int, Pen] = {}
        self._odometer_mm: dict[int, float] = {}
        for pen, mm in self.store.load_all():
            self.pens[pen.id] = pen
            self._odometer_mm[pen.id] = mm
        self._dirty: set[int] = set()
        self._flush: asyncio.TimerHandle | None = None

    def close(self) -> None:
        """Write what is left (blocking; at shutdown) and close the store."""
        if self._flush is not None:
            self._flush.cancel()
        if self._dirty:
            self.store.submit(self.store.set_odometers, self._take_dirty()).result()
        self.store.close()

    # ---- reading --------------------------------------------------------------------

    def list(self) -> list[dict[str, Any]]:
        return [self._public(pen) for pen in self.pens.values()]

    def get(self, ref: int | str) -> Pen:
        """A pen by id or (case-insensitive) name; 404 naming the known ones."""
        pen = self.find(ref)
        if pen is None:
            known = ", ".join(f"{p.id} {p.name!r}" for p in self.pens.values()) or "none"
            raise Refused(404, f"no pen {ref!r}; the library has: {known}")
        return pen

    def find(self, ref: int | str | None) -> Pen | None:
        """A pen by id (an int), or by name, else id (a string); None if none."""
        if isinstance(ref, int):
            pen = self.pens.get(ref)
        elif isinstance(ref, str):
            text = ref.strip()
            pen = next((p for p in self.pens.values() if p.name.casefold() == text.casefold()),
                       None)  # fmt: skip
            if pen is None and text.isdecimal():
                pen = self.pens.get(int(text))
        else:
            pen = None
        return self._with_odometer(pen) if pen else None

    def odometer_mm(self, pen_id: int) -> float:
        return self._odometer_mm.get(pen_id, 0.0)

    def public(self, pen: Pen) -> dict[str, Any]:
        return self._public(pen)

    def _with_odometer(self, pen: Pen) -> Pen:
        return pen.model_copy(update={"odometer_m": round(self.odometer_mm(pen.id) / 1000, 4)})

    def _public(self, pen: Pen) -> dict[str, Any]:
        return self._with_odometer(pen).model_dump(mode="json")

    # ---- changes ----------------------------------------------------------------------

    async def create(self, spec: PenSpec) -> Pen:
        self._unique(spec.name, None)
        data = spec.model_dump()
        try:
            pen_id = await asyncio.wrap_future(self.store.submit(self.store.insert, spec.name,
                                                                 data))  # fmt: skip
        except sqlite3.IntegrityError as exc:
            raise Refused(409, f"a pen named {spec.name!r} exists already") from exc
        pen = Pen(id=pen_id, **data)
        self.pens[pen_id] = pen
        self._odometer_mm[pen_id] = 0.0
        log.info("pen %d (%s) added", pen_id, pen.name)
        self._changed()
        return self._with_odometer(pen)

    async def update(self, ref: int | str, patch: PenPatch) -> Pen:
        pen = self.get(ref)
        changes = patch.model_dump(exclude_unset=True)
        for required in ("name", "colour", "up_us", "down_us"):
            if required in changes and changes[required] is None:
                raise Refused(422, f"{required}: a pen always has one; it cannot be null")
        if "name" in changes:
            self._unique(changes["name"], pen.id)
        updated = Pen.model_validate({**pen.model_dump(), **changes})
        data = PenSpec.model_validate(updated.model_dump(exclude={"id", "odometer_m"}))
        await asyncio.wrap_future(self.store.submit(self.store.update, pen.id, updated.name,
                                                    data.model_dump()))  # fmt: skip
        self.pens[pen.id] = updated
        self._changed()
        return self._with_odometer(updated)

    async def delete(self, ref: int | str) -> None:
        pen = self.get(ref)
        await asyncio.wrap_future(self.store.submit(self.store.delete, pen.id))
        del self.pens[pen.id]
        self._odometer_mm.pop(pen.id, None)
        self._dirty.discard(pen.id)
        log.info("pen %d (%s) deleted", pen.id, pen.name)
        self._changed()

    async def reset(self, ref: int | str) -> Pen:
        """The odometer back to zero (a new pen, or refilled)."""
        pen = self.get(ref)
        self._odometer_mm[pen.id] = 0.0
        self._dirty.discard(pen.id)
        await asyncio.wrap_future(self.store.submit(self.store.set_odometers, {pen.id: 0.0}))
        log.info("pen %d (%s): odometer reset", pen.id, pen.name)
        self._changed()
        return self._with_odometer(pen)

    def _unique(self, name: str, own_id: int | None) -> None:
        other = self.find(name)
        if other is not None and other.id != own_id and other.name.casefold() == name.casefold():
            raise Refused(409, f"a pen named {name!r} exists already (id {other.id})")

    def _changed(self) -> None:
        self.events.publish({"type": "pens", "pens": self.list()})

    # ---- the odometer -------------------------------------------------------------------

    def drawn(self, pen_id: int, mm: float) -> None:
        """`mm` more pen-down millimetres drawn with pen `pen_id` (on the event loop)."""
        if pen_id not in self.pens or mm <= 0:
            return
        self._odometer_mm[pen_id] = self._odometer_mm.get(pen_id, 0.0) + mm
        self._dirty.add(pen_id)
        if self._flush is None:
            self._flush = asyncio.get_running_loop().call_later(FLUSH_S, self.flush)

    def flush(self) -> None:
        """Write the changed odometers now (one transaction, on the writer thread)."""
        if self._flush is not None:
            self._flush.cancel()
            self._flush = None
        if self._dirty:
            self.store.submit(self.store.set_odometers, self._take_dirty())
            self._changed()

    def _take_dirty(self) -> dict[int, float]:
        odometers = {pen_id: self._odometer_mm[pen_id] for pen_id in self._dirty
                     if pen_id in self._odometer_mm}  # fmt: skip
        self._dirty.clear()
        return odometers

    # ---- layers and their pens ---------------------------------------------------------

    def layer_pen(self, layer: Layer) -> Pen | None:
        """The pen a job layer names (None if none, or it was deleted since)."""
        ref = layer.pen
        return self.find(ref) if isinstance(ref, int) else None

    def default_pen(self, layer: Layer) -> int | None:
        """The pen whose name is the layer's name, else whose colour is its colour."""
        name = layer.name.casefold()
        colour = layer.colour.casefold()
        for pen in self.pens.values():
            if name and pen.name.casefold() == name:
                return pen.id
        for pen in self.pens.values():
            if colour and pen.colour and pen.colour == colour:
                return pen.id
        return None

    def assign(self, layers: list[Layer], wanted: dict[str, Any] | None = None,
               kept: list[Layer] | None = None) -> None:  # fmt: skip
        """Give every layer its `pen` (a pen id or None): the one `wanted` names for it
        (by 1-based number or layer name), else the one it had in `kept` (the layers
        before a re-import), else the default. A bad layer or pen is refused (422) before
        anything changes."""
        chosen: dict[int, int | None] = {}
        for key, ref in (wanted or {}).items():
            index = self._layer_index(layers, key)
            chosen[index] = None if ref is None else self._pen_ref(ref, key).id
        for index, layer in enumerate(layers):
            if index in chosen:
                layer.pen = chosen[index]
            elif kept is not None and index < len(kept):
                layer.pen = kept[index].pen
            else:
                layer.pen = self.default_pen(layer)

    def _pen_ref(self, ref: Any, key: str) -> Pen:
        pen = self.find(ref)
        if pen is None:
            known = ", ".join(repr(p.name) for p in self.pens.values()) or "none"
            raise Refused(422, f"pens: layer {key!r}: no pen {ref!r} (the library has: {known})")
        return pen

    @staticmethod
    def _layer_index(layers: list[Layer], key: str) -> int:
        key = str(key).strip()
        if key.isdecimal() and 1 <= int(key) <= len(layers):
            return int(key) - 1
        for index, layer in enumerate(layers):
            if layer.name.casefold() == key.casefold():
                return index
        names = ", ".join(f"{i + 1} {layer.name!r}" for i, layer in enumerate(layers))
        raise Refused(422, f"pens: the job has no layer {key!r}; its layers: {names or 'none'}")
