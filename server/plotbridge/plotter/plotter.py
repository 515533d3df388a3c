"""One board as a unit: its link task, its runner, its machine state, its stop.

A plotter publishes its machine reports and console lines (each carrying its
name), and a `plotter` message when it becomes free to take a job (the queue
dispatches on it).
Nothing here knows other plotters: an emergency stop on one touches only it.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import re
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from plotbridge import settings_meta
from plotbridge.errors import Refused
from plotbridge.events import EventHub
from plotbridge.jobs.lifecycle import Lifecycle
from plotbridge.jobs.model import AfterJob, Job
from plotbridge.pens import PenLibrary
from plotbridge.plotter.board import MOVING_STATES, READY_STATE
from plotbridge.plotter.consolelog import ConsoleLog
from plotbridge.plotter.link import CommandError, Link, LinkDown, LinkEvent
from plotbridge.plotter.runner import Runner
from plotbridge.virtual import VirtualPlotter

log = logging.getLogger("plotbridge.plotter")

MACHINE_INTERVAL = 0.1  # s between machine reports while moving (the contract asks >= 5 Hz)
HOMING_S = 120.0  # s a homing cycle may take on the largest work area
CONSOLE_FORBIDDEN = "?!~\x18\r\n"  # realtime bytes and line ends: not in a console line
CONSOLE_REALTIME = {"?": "status report", "!": "feed hold", "~": "cycle start"}
SETTING_LINE = re.compile(r"\$(\d+)\s*=\s*(\S+)")  # a console line writing one setting
# Console lines that wedge or wipe the board: sent only when confirmed (the board reads
# a `$` line with its spaces removed and in capitals, so they are compared so).
CONSOLE_CONFIRM = {
    "$SLP": "puts the board to sleep: motors off, and it answers no further line until it "
            "is reset (each console line would wait 30 s for an answer)",
    "$RST=$": "restores every $ setting to the firmware's defaults (steps/mm, speeds, "
              "pen and work area)",
    "$RST=#": "clears the stored coordinate offsets (G54-G59, G28, G30)",
    "$RST=*": "wipes the board's EEPROM: every setting and offset back to the defaults",
}


@dataclass(frozen=True)
class WorkArea:
    width: float
    height: float

    def __str__(self) -> str:
        return f"{self.width:g} x {self.height:g} mm"


class Plotter:
    def __init__(self, name: str, link: Link, events: EventHub, jobs_dir: Path,
                 lifecycle: Lifecycle, *,
                 virtual: VirtualPlotter | None = None, work_area: WorkArea | None = None,
                 profile: str | None = None, home_on_connect: bool = False,
                 after_job: AfterJob = "none",
                 park: tuple[float, float] = (0.0, 0.0),
                 pens: PenLibrary | None = None) -> None:  # fmt: skip
        self.name = name
        self.link = link
        self.events = events
        self.virtual = virtual
        self.configured_area = work_area
        self.profile = profile  # the board profile configured for it (None: the default)
        self.home_on_connect = home_on_connect
        self.console_log = ConsoleLog(name, events.publish)
        self.runner = Runner(name, link, jobs_dir, lifecycle, self._free,
                             after_job=after_job, park=park, pens=pens)  # fmt: skip
        self._tracing: str | None = None  # a frame trace under way
        self._was_free = False
        self._task: asyncio.Task[None] | None = None
        self._homing: asyncio.Task[None] | None = None
        self._unsubscribe: Callable[[], None] | None = None
        self._last_machine: dict[str, Any] | None = None
        self._last_machine_sent = 0.0

    # ---- lifecycle ------------------------------------------------------------------

    def start(self) -> None:
        self._unsubscribe = self.link.subscribe(self._on_link_event)
        self._task = asyncio.create_task(self.link.run(), name=f"link-{self.name}")

    async def stop(self) -> None:
        if self._unsubscribe:
            self._unsubscribe()
        await self.runner.close()
        for task in (self._homing, self._task):
            if task:
                task.cancel()
                with contextlib.suppress(BaseException):
                    await task

    # ---- state ----------------------------------------------------------------------

    @property
    def job(self) -> Job | None:
        return self.runner.job

    @property
    def state(self) -> str:
        status = self.link.status
        return (status.state if status.connected else None) or "Disconnected"

    @property
    def work_area(self) -> WorkArea | None:
        """The configured work area, else the board's max travel ($130, $131)."""
        if self.configured_area is not None:
            return self.configured_area
        width, height = self.link.settings.get(130), self.link.settings.get(131)
        if width and height:
            return WorkArea(width, height)
        return None

    def import_model(self) -> dict[str, Any]:
        """What an import plans for on this plotter, as MachineProfile.for_board takes it
        (plain values: it goes to an import worker): the board's settings with the work
        area in $130/$131, its `$I` version and profile, and, once `$I` has been read,
        its planner's depth and whether it reports the executing line."""
        settings = dict(self.link.settings)
        if (area := self.work_area) is not None:
            settings[130], settings[131] = area.width, area.height
        facts = self.link.facts
        return {"settings": settings, "firmware": self.link.status.firmware,
                "profile": self.profile,
                "planner_blocks": facts.planner_blocks if facts.reported else 0,
                "line_numbers": facts.line_numbers if facts.reported else None}

    def fits(self, job: Job) -> bool:
        area = self.work_area
        return area is None or job.bounds is None or job.bounds.fits(area.width, area.height)

    def not_ready(self) -> str | None:
        """Why no job can start on this plotter now, or None when one can."""
        if self.job is not None:
            return f"{self.name} runs job {self.job.id} ({self.job.name})"
        if busy := self.runner.busy or self._tracing:
            return busy
        state = self.state
        if state == "Disconnected":
            return f"{self.name} is not connected; check the cable or power"
        if state == "Alarm":
            return f"{self.name} is in Alarm: home it ($H) or unlock it ($X) first"
        if state != READY_STATE:
            return f"{self.name} is {state}; wait until it is Idle"
        return None

    def machine(self) -> dict[str, Any]:
        """The machine object (DESIGN.md)."""
        status = self.link.status
        return {
            "connected": status.connected,
            "state": self.state,
            "position": {"x": round(status.x, 3), "y": round(status.y, 3)},
            "pen": "down" if status.pen == "down" else "up",
            "firmware": status.firmware,
            "alarm": status.alarm,
            "feed": status.feed,
            "pins": status.pins or None,
            "planner_free": status.planner_free,
            "line": status.line,
        }

    def describe(self) -> dict[str, Any]:
        """The `/api/plotters` entry."""
        area = self.work_area
        job = self.job
        return {
            "name": self.name,
            "device": self.link.device,
            "virtual": self.virtual is not None,
            "work_area": {"width": area.width, "height": area.height} if area else None,
            "job": job.id if job else None,
            "progress": job.progress if job else None,
            "actions": job.actions if job else [],  # the lifecycle's, as on the job itself
            "machine": self.machine(),
        }

    # ---- stop ---------------------------------------------------------------------------

    def estop(self, source: str, origin: str | None = None) -> None:
        """Emergency stop: the reset byte goes out first, before any other work.
        `origin`: the page that pressed it (its own random id), told to every client."""
        self.reset_now()
        self.stopped(source, origin)

    def realtime(self, byte: bytes) -> None:
        """A feed hold (`!`) of a moving board, or cycle start (`~`) of a held one, for a
        board no job runs on (GRBL would take an idle board into Hold)."""
        wanted = ("Run", "Jog") if byte == b"!" else ("Hold",)
        if self.state not in wanted:
            verb = "hold" if byte == b"!" else "continue"
            raise Refused(409, f"nothing to {verb}: {self.name} is {self.state} and runs no job")
        try:
            self.link.realtime(byte)
        except LinkDown as exc:
            raise Refused(409, f"{self.name} is not connected") from exc
        log.info("%s: %s", self.name, "feed hold" if byte == b"!" else "cycle start")

    def reset_now(self) -> None:
        """The emergency stop's soft reset byte, written at once."""
        self.link.estop()

    def stopped(self, source: str, origin: str | None = None) -> None:
        """The emergency stop's bookkeeping: the job is `stopped`, the clients told who
        stopped it (every page shows the stop; the others say it came from elsewhere)."""
        log.warning("EMERGENCY STOP of %s (%s)", self.name, source)
        self.runner.stopped()
        self._send_machine(force=True)
        self.events.publish({"type": "stopped", "plotter": self.name, "origin": origin,
                             "via": source})  # fmt: skip

    # ---- board verbs (while no job runs) -------------------------------------------------

    async def send(self, action: str, line: str, wait: float = 10.0) -> list[str]:
        """One line to the board while no job runs; the lines it answered before `ok`."""
        if self.job is not None:
            raise Refused(409, f"cannot {action} while job {self.job.id} is running")
        await self.runner.exact_stop_known()  # before $H moves the carriage away
        try:
            return await self.link.command(line, timeout=wait)
        except CommandError as exc:  # error:9 is GRBL's "not in this state" (Alarm, Jog)
            status = 409 if exc.code == 9 else 422
            raise Refused(status, f"the board refused {line!r}: {exc}") from exc
        except LinkDown as exc:
            raise Refused(409, f"{self.name} is not connected") from exc
        except TimeoutError as exc:
            raise Refused(409, f"the board did not answer {line!r} within {wait:g} s") from exc

    async def trace_frame(self, job: Job) -> None:
        """Pen up around the job's bounds and back to the first corner, so the user sees
        where it will draw. The plotter takes no job meanwhile."""
        bounds = job.bounds
        if bounds is None:
            raise Refused(409, f"job {job.id} has no bounds to trace")
        if busy := self.runner.busy or self._tracing:
            raise Refused(409, busy)
        if self.state != READY_STATE:
            raise Refused(409, self.not_ready() or f"{self.name} is {self.state}")
        corners = [(bounds.min_x, bounds.min_y), (bounds.max_x, bounds.min_y),
                   (bounds.max_x, bounds.max_y), (bounds.min_x, bounds.max_y),
                   (bounds.min_x, bounds.min_y)]  # fmt: skip
        lines = ["M5", *(f"G0 X{x:.3f} Y{y:.3f}" for x, y in corners), "G4 P0"]
        self._tracing = f"{self.name} traces the frame of job {job.id}"
        self._free()
        log.info("%s: tracing the frame of job %s", self.name, job.id)
        try:
            for line in lines:  # G4 P0 is answered once the carriage has stopped
                await self.send("trace the frame", line, wait=120)
        finally:
            self._tracing = None
            self._free()

    async def jog(self, dx: float, dy: float, feed: float) -> list[str]:
        if self.job is not None:
            raise Refused(409, f"cannot jog while job {self.job.id} is running")
        if self.state not in (READY_STATE, "Jog"):
            raise Refused(409, f"cannot jog while the machine is {self.state}")
        return await self.send("jog", f"$J=G91 G21 X{dx:.3f} Y{dy:.3f} F{feed:.0f}")

    async def console(self, line: str, confirm: bool = False) -> list[str]:
        """A console line; its answer ends with the `ok` the link keeps to itself.
        `?`, `!` and `~` alone are GRBL's realtime bytes: written at once (also while a job
        runs: `!` and `~` then act as the machine's own hold and start buttons). A line
        of CONSOLE_CONFIRM is refused (428, saying what it does) unless `confirm`."""
        byte = line.strip()
        if byte in CONSOLE_REALTIME:
            try:
                self.link.realtime(byte.encode())
            except LinkDown as exc:
                raise Refused(409, "the plotter is not connected") from exc
            said = f"{byte} ({CONSOLE_REALTIME[byte]}: sent as a realtime byte)"
            self.console_log.add("tx", said)
            return [said]
        if self.job is not None:
            raise Refused(409, f"cannot send commands while job {self.job.id} is running")
        line = line.strip()
        if not line or any(ch in line for ch in CONSOLE_FORBIDDEN) or not line.isprintable():
            raise Refused(422, "one printable G-code or $ line, without realtime characters")
        effect = CONSOLE_CONFIRM.get("".join(line.split()).upper())
        if effect and not confirm:
            raise Refused(428, f"{line} {effect}; send it again confirmed to go ahead")
        if written := SETTING_LINE.fullmatch(line):
            with contextlib.suppress(ValueError):  # not a number: the board says so itself
                self.check_settings({int(written[1]): float(written[2])})
        return [*await self.send("send commands", line, wait=30), "ok"]

    @property
    def checks_ranges(self) -> bool:
        """Whether the board is ours, whose ranges settings_meta knows: it has the pen
        servo settings ($60). Stock GRBL keeps its own (other) limits."""
        return 60 in self.link.settings

    def settings(self) -> list[dict[str, Any]]:
        """The board's settings with their names, units, descriptions and ranges."""
        view = []
        for number in sorted(self.link.settings, key=settings_meta.shown_order):
            meta = settings_meta.SETTINGS.get(number)
            limits = settings_meta.RANGES.get(number) if self.checks_ranges else None
            view.append({
                "id": number, "value": self.link.settings[number],
                "name": meta.name if meta else None, "unit": meta.unit if meta else None,
                "description": meta.description if meta else None,
                "range": limits.public() if limits else None,
                "group": settings_meta.group(number),
            })  # fmt: skip
        return view

    def check_settings(self, values: dict[int, float]) -> None:
        """Refuses (422, every reason with its range) values the board would refuse,
        before any of them is written."""
        if not self.checks_ranges:
            return
        after = {**self.link.settings, **values}
        reasons = [why for number, value in values.items()
                   if (why := settings_meta.check(number, value, after))]  # fmt: skip
        if reasons:
            raise Refused(422, "; ".join(reasons))

    async def write_settings(self, values: dict[int, float]) -> list[str]:
        self.check_settings(values)
        responses: list[str] = []
        for number, value in values.items():
            text = f"{value:g}" if value != int(value) else str(int(value))
            responses += await self.send("change settings", f"${number}={text}")
        return responses

    async def trace(self) -> dict[str, Any]:
        """What the virtual plotter's pen drew (mm)."""
        if self.virtual is None:
            raise Refused(404, f"{self.name} is not a virtual plotter: it drives a real board")
        trace = await asyncio.to_thread(self.virtual.trace)
        strokes = [[[p[0], p[1]] for p in stroke] for stroke in trace.get("strokes", [])]
        return {**trace, "strokes": strokes}

    # ---- link events --------------------------------------------------------------------

    def _on_link_event(self, event: LinkEvent) -> None:
        if event.kind == "status" and event.status is not None:
            self.runner.on_status(event.status)
            self._send_machine()
            self._free()
        elif event.kind == "log":
            self._on_log(event.direction or "rx", event.line or "")
        elif event.kind == "alarm":
            log.warning("%s: board alarm %s", self.name, event.code)
            self._send_machine(force=True)
        elif event.kind == "connected":
            log.info("%s connected: %s", self.name, self.link.status.firmware)
            self._send_machine(force=True)
            if self.home_on_connect and self.job is None:
                self._homing = asyncio.create_task(self._home(time.time()),
                                                   name=f"home-{self.name}")  # fmt: skip
            self._free()
        elif event.kind == "disconnected":
            log.warning("%s disconnected: %s", self.name, event.message)
            self.runner.lost()
            self._send_machine(force=True)
            self._free()

    async def _home(self, since: float) -> None:
        """`--home-on-connect`: home a plotter that came up in Alarm (waiting jobs follow)."""
        for _ in range(60):  # the first status report of this connection (polled at 8 Hz)
            if self.link.status.updated_at > since:
                break
            await asyncio.sleep(0.05)
        if self.state != "Alarm" or self.job is not None:
            return
        log.info("%s connected in Alarm: homing (--home-on-connect)", self.name)
        try:
            await self.link.command("$H", timeout=HOMING_S)
        except Exception as exc:
            log.warning("%s: homing on connect failed: %s", self.name, exc)

    def _send_machine(self, force: bool = False) -> None:
        machine = self.machine()
        now = time.monotonic()
        due = machine["state"] in MOVING_STATES and now - self._last_machine_sent > MACHINE_INTERVAL
        if force or due or machine != self._last_machine:
            self._last_machine = machine
            self._last_machine_sent = now
            self.events.publish({"type": "machine", "plotter": self.name, "machine": machine})

    def _on_log(self, direction: str, line: str) -> None:
        if not line or line.startswith("<") or line == "?":
            return
        if self.job is not None and (direction == "tx" or line == "ok"):
            return  # a streaming job would flood the consoles; errors and messages still go
        self.console_log.add(direction, line)

    # ---- free to take a job ------------------------------------------------------------

    def _free(self) -> None:
        """Publish `{"type": "plotter", "plotter", "free"}` when whether the plotter can take
        a job now changes (the queue dispatches waiting jobs on `free`)."""
        free = self.not_ready() is None
        if free != self._was_free:
            self._was_free = free
            self.events.publish({"type": "plotter", "plotter": self.name, "free": free})
