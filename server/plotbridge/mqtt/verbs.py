"""The server verbs MQTT calls: the same ones the REST routes call (api/plotters.py,
api/jobs.py: the queue's stops and the lifecycle's verbs, jobs/actions.py). This is the one
module of the MQTT component that knows the queue and the plotters, so a change of their
interface is a change here only. MQTT acts as this bridge's own operator (people.access.MQTT):
each verb asks the role table (plotbridge.access) as a route would, and is audited."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from plotbridge.access import JOB_ACTIONS, Role, may, rule
from plotbridge.errors import Refused
from plotbridge.jobs.actions import JobActions
from plotbridge.jobs.model import Job
from plotbridge.people.access import MQTT, Access
from plotbridge.people.actor import ACTOR
from plotbridge.queue import JobQueue

MACHINE = "/api/plotters/{name}/machine/"  # the routes whose rows the plotter verbs share


class Verbs:
    def __init__(self, queue: JobQueue, actions: JobActions, access: Access) -> None:
        self.queue = queue
        self.actions = actions
        self.access = access

    def _as_mqtt(self, what: str, need: Role | None, target: str | None) -> None:
        """Refused (403) when the role table does not let MQTT's operator do `what`; else
        audited as MQTT's, and the job verbs record it as who acted."""
        if need is not None and not may(MQTT.role, need, False, False):
            self.access.audit(MQTT, what, target, {"refused": 403})
            raise Refused(403, f"{MQTT.who} is an operator: {what} needs {need.name}")
        ACTOR.set(MQTT.who)
        self.access.audit(MQTT, what, target)

    @property
    def plotters(self) -> list[str]:
        return list(self.queue.plotters)

    def snapshot(self) -> list[dict[str, Any]]:
        return self.queue.snapshot_messages()

    # ---- stops: synchronous, nothing before the reset byte ------------------------------

    def estop(self, plotter: str, source: str) -> None:
        """Refused (404) for a plotter this bridge does not have, as on REST. STOP is
        everyone's: it is recorded after it is done."""
        self.queue.estop(plotter, source)
        self._as_mqtt(f"MQTT stop ({source})", None, plotter)

    def estop_all(self, source: str) -> None:
        self.queue.estop_all(source)
        self._as_mqtt(f"MQTT stop all ({source})", None, None)

    # ---- the other buttons ------------------------------------------------------------

    def refused_by_job(self, plotter: str, verb: str) -> str | None:
        """Why the plotter's job does not allow `verb` now (its `actions`), or None."""
        job = self.queue.plotter(plotter).job
        if job is None or verb not in ("hold", "continue") or verb in job.actions:
            return None
        return f"{plotter}'s job {job.id} allows {', '.join(job.actions) or 'nothing'} now"

    def hold(self, plotter: str) -> None:
        self._as_mqtt("MQTT hold", rule("POST", MACHINE + "hold")[0], plotter)
        self.actions.hold_plotter(plotter)

    def go_on(self, plotter: str) -> None:
        self._as_mqtt("MQTT continue", rule("POST", MACHINE + "continue")[0], plotter)
        self.actions.continue_plotter(plotter)

    async def home(self, plotter: str) -> None:
        self._as_mqtt("MQTT home", rule("POST", MACHINE + "home")[0], plotter)
        await self.queue.plotter(plotter).send("home", "$H", wait=120)

    # ---- fleet jobs ---------------------------------------------------------------------

    def job(self, job_id: str) -> Job | None:
        return self.queue.jobs.get(job_id)

    def free_plotter(self, bounds: dict[str, float] | None) -> str | None:
        """A plotter that could start a job of these bounds now, or None."""
        for unit in self.queue.plotters.values():
            area = unit.work_area
            fits = bounds is None or area is None or (
                bounds["min_x"] >= 0 and bounds["min_y"] >= 0
                and bounds["max_x"] <= area.width + 1e-6 and bounds["max_y"] <= area.height + 1e-6)
            if fits and unit.not_ready() is None and not self._waiting_for(unit.name):
                return unit.name
        return None

    def _waiting_for(self, plotter: str) -> bool:
        """A local job waits to start (it goes first: the fleet takes what is left)."""
        return any(job.state == "waiting" and job.target in (None, plotter)
                   for job in self.queue.jobs.values())  # fmt: skip

    async def create(self, kind: str, source: Path | str, filename: str, name: str,
                     options: dict[str, Any], placement: dict[str, Any],
                     plotter: str | None) -> Job:  # fmt: skip
        """A new queued job from a file (moved into the job) or a pattern's name, owned by
        MQTT's operator (the fleet placed it: it waits for no approval here)."""
        self._as_mqtt("MQTT fleet job", rule("POST", "/api/jobs")[0], name)
        return await self.queue.create(kind=kind, source=source, filename=filename, name=name,
                                       options=options, placement=placement, target=plotter,
                                       owner=MQTT.who)  # fmt: skip

    async def start(self, job_id: str, plotter: str) -> Job:
        self._as_mqtt("MQTT start", JOB_ACTIONS["start"][0], job_id)
        return await self.actions.act(job_id, "start", plotter)

    async def delete(self, job_id: str) -> None:
        """The fleet's bookkeeping, not a person's delete (so not asked of the table): it
        removes only the local copies it placed here, and a job an upload handed to it
        (`fleet=true`, whose file it holds now). Audited as MQTT's."""
        self._as_mqtt("MQTT fleet drop", None, job_id)
        await self.actions.act(job_id, "delete")

    def source(self, job_id: str) -> tuple[str, str, str, dict[str, Any], dict[str, Any]]:
        """What a job was made from: its kind, its original file's path (or the pattern's
        name), the file's name, the import options and the placement."""
        job = self.queue.get(job_id)
        source = str(self.queue.importer.jobs_dir / job.id / job.source) if job.kind == "file" \
            else job.source
        return job.kind, source, job.filename, dict(job.options), dict(job.placement)
