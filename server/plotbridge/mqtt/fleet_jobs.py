"""One queue across the fleet: jobs uploaded with `fleet=true` go to the first free plotter
of any bridge whose work area fits them, in the fleet's queue order (oldest offer first).

The origin bridge (where the job was uploaded) is the one authority on its jobs, so a job
is never plotted twice and never lost:

1. the origin offers the job (retained on plotbridge/FLEET/jobs/ID: name, bounds, age);
2. a bridge with a free plotter it fits claims it (only bridges that accept `start`);
3. the origin grants it to the first claimant, sending the file in the grant (the broker
   already authenticates and authorizes every bridge: no second credential, and bridges in
   rooms that cannot reach each other still work), and denies the others;
4. the taker imports it for its plotter and answers "taken"; the origin answers "go" if
   the job is still granted to it (else "revoke": the taker deletes its copy);
5. only on "go" does the taker start it, and from then on the job is the taker's: a
   bridge that dies mid-job leaves it interrupted and resumable there, as any job.

A taker that dies before "go" (its last will says offline), or does not answer within
GRANT_TIMEOUT, gets the job taken back and offered again. A taker that restarts asks
again about the jobs it had imported (the origin may have said "go" as it died), and
starts those it was told to go with but had not started.
"""

from __future__ import annotations

import asyncio
import base64
import json
import logging
import time
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from plotbridge.errors import Refused
from plotbridge.jobs.lifecycle import SETTLED
from plotbridge.mqtt.connection import Connection
from plotbridge.mqtt.settings import MqttSettings
from plotbridge.mqtt.topics import Topics
from plotbridge.mqtt.verbs import Verbs

log = logging.getLogger("plotbridge.mqtt.fleet")

CLAIM_TIMEOUT = 10.0  # s a claim waits for the origin's answer
GRANT_TIMEOUT = 120.0  # s a granted job may take to be imported and taken
KEPT = 50  # finished fleet jobs an origin remembers
NAME = r"^[A-Za-z0-9_-]{1,64}$"


class Edge(BaseModel):
    model_config = ConfigDict(extra="ignore")


class Offer(Edge):
    origin: str = Field(pattern=NAME)
    id: str = Field(pattern=NAME)
    name: str = Field(max_length=200)
    bounds: dict[str, float] | None = None
    created_at: float


class ToOrigin(Edge):
    type: Literal["claim", "taken", "decline"]
    job: str = Field(pattern=NAME)
    bridge: str = Field(pattern=NAME)
    plotter: str = Field(pattern=NAME)


class ToTaker(Edge):
    type: Literal["grant", "deny", "go", "revoke"]
    job: str = Field(pattern=NAME)
    origin: str = Field(pattern=NAME)
    plotter: str | None = None
    name: str = ""
    kind: Literal["file", "pattern"] = "file"
    filename: str = ""
    options: dict[str, Any] = {}
    placement: dict[str, Any] = {}
    data: str = ""  # the file, base64 (kind "file"), or the pattern's name


class Party:
    """What the origin and the taker share: the settings, the link, their records on disk
    (written by one writer task, the latest version wins) and their background tasks."""

    FILE = ""

    def __init__(self, settings: MqttSettings, topics: Topics, connection: Connection,
                 verbs: Verbs, folder: Path) -> None:  # fmt: skip
        self.settings = settings
        self.topics = topics
        self.connection = connection
        self.verbs = verbs
        self.folder = folder
        self.records: dict[str, dict[str, Any]] = self._load()
        self._tasks: set[asyncio.Task[None]] = set()
        self._dirty = False
        self._writer: asyncio.Task[None] | None = None

    def _load(self) -> dict[str, dict[str, Any]]:
        path = self.folder / self.FILE
        try:
            data = json.loads(path.read_text()) if path.exists() else {}
        except (OSError, ValueError) as exc:
            log.error("fleet jobs: %s unreadable (%s); starting without it", path, exc)
            return {}
        return data if isinstance(data, dict) else {}

    def _save(self) -> None:
        self._dirty = True
        if self._writer is None or self._writer.done():
            self._writer = asyncio.create_task(self._write())

    async def _write(self) -> None:
        while self._dirty:
            self._dirty = False
            await asyncio.to_thread(_replace, self.folder / self.FILE, json.dumps(self.records))

    def _spawn(self, work: Any) -> None:
        task = asyncio.create_task(work)
        self._tasks.add(task)
        task.add_done_callback(self._done)

    def _done(self, task: asyncio.Task[None]) -> None:
        self._tasks.discard(task)
        if not task.cancelled() and task.exception() is not None:
            log.error("fleet jobs: %s", task.exception())

    def close(self) -> None:
        for task in self._tasks:
            task.cancel()

    def _garbage(self, where: str, exc: Exception) -> None:
        self.connection.problems.warn(f"fleet-{where}", "MQTT: ignoring a malformed fleet "
                                      "message on %s (%s); further ones are not logged", where,
                                      str(exc).splitlines()[0])  # fmt: skip


class FleetOrigin(Party):
    """Our fleet jobs, as the one authority on them (steps 1, 3, 4 and taking back)."""

    FILE = "own.json"

    async def offer(self, job: dict[str, Any]) -> dict[str, Any]:
        """Take an imported local job into the fleet's queue: its file moves to the fleet
        folder, the local job goes (the fleet holds it now); the upload's answer."""
        kind, source, filename, options, placement = self.verbs.source(job["id"])
        record = {"id": job["id"], "name": job["name"], "bounds": job.get("bounds"),
                  "created_at": time.time(), "kind": kind, "filename": filename,
                  "options": options, "placement": placement, "state": "offered",
                  "bridge": None, "plotter": None, "progress": 0.0, "job_state": "queued",
                  "since": time.time()}  # fmt: skip
        if kind == "file":
            await asyncio.to_thread(_copy, Path(source), self.folder / job["id"] / "original")
        else:
            record["pattern"] = source
        await self.verbs.delete(job["id"])
        self.records[job["id"]] = record
        self._save()
        self._publish_offer(record)
        log.info("fleet job %s (%s) offered to the fleet", job["id"], job["name"])
        return {**job, "state": "queued", "fleet": self.public(record)}

    def _publish_offer(self, record: dict[str, Any]) -> None:
        offer = Offer(origin=self.settings.bridge, id=record["id"], name=record["name"],
                      bounds=record["bounds"], created_at=record["created_at"])  # fmt: skip
        self.connection.publish(self.topics.offer(record["id"]), offer.model_dump_json())

    def _withdraw(self, job: str) -> None:
        self.connection.publish(self.topics.offer(job), b"")

    def to_origin(self, payload: bytes) -> None:
        try:
            message = ToOrigin.model_validate_json(payload)
        except ValidationError as exc:
            return self._garbage("claim", exc)
        record = self.records.get(message.job)
        if record is None:
            return self._send(message.bridge, "deny", message.job)
        if message.type == "claim":
            if record["state"] != "offered":
                return self._send(message.bridge, "deny", message.job)
            record.update(state="granted", bridge=message.bridge, plotter=message.plotter,
                          since=time.time())  # fmt: skip
            self._save()
            log.info("fleet job %s granted to %s/%s", message.job, message.bridge,
                     message.plotter)  # fmt: skip
            self._spawn(self._grant(record))
        elif message.type == "decline":
            if record["state"] == "granted" and record["bridge"] == message.bridge:
                self._reoffer(record, f"{message.bridge} could not import it")
        elif record["state"] in ("granted", "committed") and record["bridge"] == message.bridge:
            if record["state"] == "granted":
                record.update(state="committed", since=time.time())
                self._withdraw(message.job)
                self._save()
                log.info("fleet job %s goes to %s/%s", message.job, message.bridge,
                         message.plotter)  # fmt: skip
            self._send(message.bridge, "go", message.job)
        else:
            self._send(message.bridge, "revoke", message.job)

    async def _grant(self, record: dict[str, Any]) -> None:
        data = record.get("pattern", "")
        if record["kind"] == "file":
            raw = await asyncio.to_thread((self.folder / record["id"] / "original").read_bytes)
            data = base64.b64encode(raw).decode()
        grant = ToTaker(type="grant", job=record["id"], origin=self.settings.bridge,
                        plotter=record["plotter"], name=record["name"], kind=record["kind"],
                        filename=record["filename"], options=record["options"],
                        placement=record["placement"], data=data)  # fmt: skip
        if not await self.connection.send_now(self.topics.grant(record["bridge"]),
                                              grant.model_dump_json()):  # fmt: skip
            self._reoffer(record, "the grant could not be sent")

    def _send(self, taker: str, kind: str, job: str) -> None:
        message = ToTaker(type=kind, job=job, origin=self.settings.bridge)  # type: ignore[arg-type]
        self.connection.event(self.topics.grant(taker), message.model_dump_json())

    def _reoffer(self, record: dict[str, Any], why: str) -> None:
        log.warning("fleet job %s: taken back from %s (%s); offered again", record["id"],
                    record["bridge"], why)  # fmt: skip
        record.update(state="offered", bridge=None, plotter=None, since=time.time())
        self._save()
        self._publish_offer(record)

    def bridge_offline(self, bridge: str) -> None:
        for record in self.records.values():
            if record["state"] == "granted" and record["bridge"] == bridge:
                self._reoffer(record, f"{bridge} went offline before starting it")

    def placed(self, job: str, payload: bytes) -> None:
        """The taker's report on one of our jobs: where it runs, its state and progress."""
        record = self.records.get(job)
        if record is None or not payload:
            return
        try:
            data = json.loads(payload)
            state, progress = str(data["state"]), float(data["progress"])
        except (ValueError, KeyError, TypeError):
            return self._garbage("jobs", ValueError("needs state and progress"))
        record.update(job_state=state[:32], progress=progress)
        if state in SETTLED:
            self._forget_old()
            self._save()

    def _forget_old(self) -> None:
        """Keep the records of the last KEPT finished fleet jobs (the Fleet tab lists them)."""
        finished = [r for r in sorted(self.records.values(), key=lambda r: r["created_at"])
                    if r["state"] == "committed" and r["job_state"] in SETTLED]
        for record in finished[:-KEPT]:
            del self.records[record["id"]]
            self.connection.publish(self.topics.placed(record["id"]), b"")

    def poll(self) -> None:
        """Take back what was granted and not taken in time."""
        for record in list(self.records.values()):
            if record["state"] == "granted" and time.time() - record["since"] > GRANT_TIMEOUT:
                self._reoffer(record, f"no answer in {GRANT_TIMEOUT:g} s")

    def recover(self) -> None:
        """After a (re)connection: our jobs on offer, offered again."""
        for record in self.records.values():
            if record["state"] == "offered":
                self._publish_offer(record)

    # ---- views ---------------------------------------------------------------------------

    def public(self, record: dict[str, Any]) -> dict[str, Any]:
        """`settled`: placed, and its job there has come to rest (the lifecycle's word)."""
        keep = ("id", "name", "state", "bridge", "plotter", "job_state", "progress")
        settled = record["state"] == "committed" and record.get("job_state") in SETTLED
        return {**{key: record.get(key) for key in keep}, "settled": settled}

    def describe(self) -> list[dict[str, Any]]:
        ordered = sorted(self.records.values(), key=lambda r: r["created_at"])
        return [self.public(record) for record in ordered]


class FleetTaker(Party):
    """Other bridges' (and our own) fleet jobs, as a bridge that may take them (2, 4, 5)."""

    FILE = "taken.json"

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        self.offers: dict[str, Offer] = {}  # every job on offer in the fleet
        self._claim: tuple[str, float] | None = None  # (job, when) of our open claim
        self._declined: set[str] = set()  # jobs we could not import: not claimed again

    def offered(self, job: str, payload: bytes) -> None:
        if not payload:
            self.offers.pop(job, None)
            return
        try:
            self.offers[job] = Offer.model_validate_json(payload)
        except ValidationError as exc:
            self._garbage("jobs", exc)

    def poll(self) -> None:
        """Claim the fleet's oldest job that fits a free plotter of ours (one at a time)."""
        now = time.monotonic()
        if self._claim is not None and now - self._claim[1] < CLAIM_TIMEOUT:
            return
        self._claim = None
        if not self.settings.allows("start") or not self.connection.connected:
            return
        for offer in sorted(self.offers.values(), key=lambda o: (o.created_at, o.id)):
            if offer.id in self.records or offer.id in self._declined:
                continue
            plotter = self.verbs.free_plotter(offer.bounds)
            if plotter is None:
                continue
            self._claim = (offer.id, now)
            message = ToOrigin(type="claim", job=offer.id, bridge=self.settings.bridge,
                               plotter=plotter)  # fmt: skip
            self.connection.event(self.topics.claim(offer.origin), message.model_dump_json())
            return

    def to_taker(self, payload: bytes) -> None:
        try:
            message = ToTaker.model_validate_json(payload)
        except ValidationError as exc:
            return self._garbage("grant", exc)
        if message.type == "grant":
            if not self.settings.allows("start") or self._claim is None \
                    or self._claim[0] != message.job:
                return self._garbage("grant", ValueError(f"a grant of {message.job} we did "
                                                         "not claim"))
            self._claim = (message.job, time.monotonic() + GRANT_TIMEOUT)  # no other claim
            self._spawn(self._take(message))
        elif message.type == "deny":
            if self._claim and self._claim[0] == message.job:
                self._claim = None
        elif message.type == "go":
            self._spawn(self._go(message.job))
        elif message.type == "revoke":
            self._spawn(self._drop(message.job))

    async def _take(self, grant: ToTaker) -> None:
        """Import the granted job for its plotter; tell the origin; start only on "go"."""
        try:
            if grant.kind == "file":
                path = self.folder / f".grant-{grant.job}"
                await asyncio.to_thread(_write, path, base64.b64decode(grant.data))
                source: Path | str = path
            else:
                source = grant.data
            job = await self.verbs.create(grant.kind, source, grant.filename or grant.name,
                                          grant.name, grant.options, grant.placement,
                                          grant.plotter)  # fmt: skip
        except (Refused, ValueError, OSError) as exc:
            log.warning("fleet job %s from %s cannot be taken: %s", grant.job, grant.origin,
                        getattr(exc, "detail", exc))  # fmt: skip
            self._claim = None
            self._declined.add(grant.job)
            message = ToOrigin(type="decline", job=grant.job, bridge=self.settings.bridge,
                               plotter=grant.plotter or "any")  # fmt: skip
            self.connection.event(self.topics.claim(grant.origin), message.model_dump_json())
            return
        self.records[grant.job] = {"origin": grant.origin, "local": job.id,
                                 "plotter": grant.plotter, "phase": "imported"}  # fmt: skip
        self._save()
        self._ask(grant.job)

    def _ask(self, job: str) -> None:
        record = self.records[job]
        message = ToOrigin(type="taken", job=job, bridge=self.settings.bridge,
                           plotter=record["plotter"] or "any")  # fmt: skip
        self.connection.event(self.topics.claim(record["origin"]), message.model_dump_json())

    async def _go(self, job: str) -> None:
        record = self.records.get(job)
        self._claim = None
        if record is None:
            return
        local = self.verbs.job(record["local"])
        if record["phase"] == "imported" and local is not None and local.state == "queued":
            record["phase"] = "go"
            self._save()
            started = await self.verbs.start(local.id, record["plotter"])
            log.info("fleet job %s from %s: %s on %s", job, record["origin"], started.state,
                     record["plotter"])  # fmt: skip

    async def _drop(self, job: str) -> None:
        record = self.records.pop(job, None)
        self._claim = None
        if record is not None:
            self._save()
            if self.verbs.job(record["local"]) is not None:
                await self.verbs.delete(record["local"])

    def recover(self) -> None:
        """After a (re)connection: ask again about imported jobs, start those told to go."""
        for job, record in list(self.records.items()):
            local = self.verbs.job(record["local"])
            if local is None:
                del self.records[job]
                self._save()
            elif record["phase"] == "imported":
                self._ask(job)
            elif local.state == "queued":
                self.verbs.start(local.id, record["plotter"])

    def on_event(self, message: dict[str, Any]) -> None:
        """Our local copies' progress, reported to their origins."""
        if message.get("type") != "job":
            return
        job = message["job"]
        for fleet_id, record in list(self.records.items()):
            if record["local"] == job["id"] and record["phase"] == "go":
                report = {"bridge": self.settings.bridge, "plotter": job.get("plotter"),
                          "state": job["state"], "progress": job.get("progress", 0)}
                self.connection.publish(self.topics.placed(fleet_id, record["origin"]),
                                        json.dumps(report))  # fmt: skip
                if job["state"] in SETTLED - {"stopped"}:
                    del self.records[fleet_id]
                    self._save()


def _replace(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}")
    partial.write_text(text)
    partial.replace(path)


def _copy(source: Path, target: Path) -> None:
    _write(target, source.read_bytes())


def _write(target: Path, data: bytes) -> None:
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_bytes(data)
