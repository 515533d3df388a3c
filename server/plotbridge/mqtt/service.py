"""The MQTT component: Home Assistant discovery and state, commands from the broker, the
fleet view and the fleet's stops. Created once by the app when MQTT is configured.

A STOP from the broker (a plotter's, a bridge's STOP ALL, the fleet's STOP EVERYTHING) is
acted on inside the callback that reads it off the socket, before anything queued; a
retained message on a command topic is never obeyed (it would replay at every connect).
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import Callable
from pathlib import Path
from typing import Any

from aiomqtt import Message

from plotbridge.errors import Refused
from plotbridge.events import EventHub
from plotbridge.mqtt.connection import Connection
from plotbridge.mqtt.discovery import Discovery
from plotbridge.mqtt.fleet import FleetView
from plotbridge.mqtt.fleet_jobs import FleetOrigin, FleetTaker
from plotbridge.mqtt.settings import MqttSettings
from plotbridge.mqtt.telemetry import Telemetry
from plotbridge.mqtt.topics import PLOTTER_VERBS, Topics
from plotbridge.mqtt.verbs import Verbs

log = logging.getLogger("plotbridge.mqtt")


class MqttService:
    def __init__(self, settings: MqttSettings, verbs: Verbs, events: EventHub,
                 public_url: str, data_dir: Path) -> None:  # fmt: skip
        self.settings = settings
        self.verbs = verbs
        self.events = events
        self.url = settings.public_url or public_url
        self.topics = Topics(settings.fleet, settings.bridge)
        self.discovery = Discovery(self.topics, settings.discovery_prefix, self.url)
        self.telemetry = Telemetry(verbs.plotters, self._send_state, self._send_event)
        self.connection = Connection(
            settings, client_id=f"plotbridge-{settings.fleet}-{settings.bridge}",
            will_topic=self.topics.status(), on_connected=self._connected,
            on_message=self._message, urgent=self._urgent,
            subscriptions=[*self.topics.subscriptions(), self.discovery.our_configs],
        )  # fmt: skip
        self.fleet = FleetView(self.connection.problems)
        parts = (settings, self.topics, self.connection, verbs, data_dir / "fleet")
        self.origin, self.taker = FleetOrigin(*parts), FleetTaker(*parts)
        self._ticker: asyncio.Task[None] | None = None
        self._configs = self.discovery.configs(verbs.plotters)
        self._unsubscribe: Callable[[], None] | None = None
        self._tasks: set[asyncio.Task[None]] = set()

    # ---- lifecycle ----------------------------------------------------------------------

    def start(self) -> None:
        for message in self.verbs.snapshot():
            self.telemetry.on_event(message)
        self._unsubscribe = self.events.subscribe(self._on_event)
        self.connection.start()
        self._ticker = asyncio.create_task(self._tick(), name="fleet-jobs")
        log.info("MQTT: bridge %s of fleet %s, broker %s", self.settings.bridge,
                 self.settings.fleet, self.connection.where)  # fmt: skip

    async def close(self) -> None:
        if self._unsubscribe:
            self._unsubscribe()
        self.telemetry.close()
        if self._ticker is not None:
            self._ticker.cancel()
        self.origin.close()
        self.taker.close()
        await self.connection.close()

    async def _tick(self) -> None:
        """Each second: fleet jobs granted and not taken in time, and the fleet view
        sent to the pages (`{"type": "fleet"}`, when it changed: no page polls it)."""
        shown = None
        while True:
            await asyncio.sleep(1.0)
            self.origin.poll()
            self.taker.poll()
            view = self.describe()
            if view != shown:
                shown = view
                self.events.publish({"type": "fleet", "fleet": view})

    def _on_event(self, message: dict[str, Any]) -> None:
        self.telemetry.on_event(message)
        self.taker.on_event(message)

    async def _connected(self) -> None:
        """Everything retained, again: the bridge, its configs, its plotters' states."""
        publish = self.connection.publish
        publish(self.topics.info(), json.dumps({"bridge": self.settings.bridge, "url": self.url,
                                                "plotters": self.verbs.plotters}))
        for topic, config in self._configs.items():
            publish(topic, config)
        self.telemetry.resend()
        self.origin.recover()
        self.taker.recover()

    def _send_state(self, plotter: str, payload: str) -> None:
        self.connection.publish(self.topics.state(plotter), payload)

    def _send_event(self, plotter: str, payload: str) -> None:
        self.connection.event(self.topics.event(plotter), payload)

    # ---- incoming -----------------------------------------------------------------------

    def _urgent(self, message: Message) -> bool:
        """The stops, acted on as they come off the socket; True: handled (or dropped)."""
        levels = self.topics.parse(message.topic.value)
        if levels is None or not _is_command(levels):
            return False
        if message.retain:
            self.connection.problems.warn(
                "retained-command", "MQTT: ignoring a retained command on %s (commands are "
                "never retained; clear it with an empty retained message)", message.topic.value)
            return True
        own = self.settings.bridge
        if levels == ["cmd", "stop_all"]:
            if _sender(message.payload) != own:  # our own STOP EVERYTHING already acted here
                self.verbs.estop_all("MQTT, the fleet's STOP EVERYTHING")
            return True
        if levels == [own, "cmd", "stop_all"]:
            self.verbs.estop_all("MQTT, STOP ALL of the bridge")
            return True
        if (len(levels) == 5 and levels[0] == own and levels[1] == "plotter"
                and levels[3] == "cmd" and levels[4] == "stop"):
            if levels[2] in self.verbs.plotters:
                self.verbs.estop(levels[2], "MQTT")
            return True
        return False

    def _message(self, message: Message) -> None:
        topic = message.topic.value
        payload = message.payload if isinstance(message.payload, bytes) else str(
            message.payload or "").encode()
        if topic.startswith(self.settings.discovery_prefix + "/"):
            if payload and topic not in self._configs:
                self.connection.problems.warn("stale-configs", "MQTT: removing retained "
                                              "discovery configs this bridge does not publish "
                                              "(the first: %s)", topic)  # fmt: skip
                self.connection.publish(topic, b"")
            return
        levels = self.topics.parse(topic)
        if levels is None:
            return
        own = self.settings.bridge
        if len(levels) == 2 and levels[1] == "status":
            self.fleet.status(levels[0], payload)
            if payload == b"offline":
                self.origin.bridge_offline(levels[0])
        elif len(levels) == 2 and levels[0] == "jobs":
            self.taker.offered(levels[1], payload)
        elif levels == [own, "claim"] and not message.retain:
            self.origin.to_origin(payload)
        elif levels == [own, "grant"] and not message.retain:
            self.taker.to_taker(payload)
        elif len(levels) == 3 and levels[:2] == [own, "jobs"]:
            self.origin.placed(levels[2], payload)
        elif len(levels) == 2 and levels[1] == "info":
            self.fleet.info(levels[0], payload)
        elif len(levels) == 4 and levels[1] == "plotter" and levels[3] == "state":
            if levels[0] == own and levels[2] not in self.verbs.plotters and payload:
                self.connection.publish(topic, b"")  # a plotter this bridge no longer has
            self.fleet.state(levels[0], levels[2], payload)
        elif (len(levels) == 5 and levels[0] == own and levels[3] == "cmd"
              and not message.retain):
            self._command(levels[2], levels[4])

    def _command(self, plotter: str, verb: str) -> None:
        if plotter not in self.verbs.plotters or verb not in PLOTTER_VERBS:
            self.connection.problems.warn("unknown-command", "MQTT: ignoring command %s for "
                                          "plotter %s (unknown)", verb, plotter)  # fmt: skip
            return
        if not self.settings.allows(verb):
            self.connection.problems.warn(f"refused-{verb}", "MQTT: the broker may not send "
                                          "%s (not in the accepted commands)", verb)  # fmt: skip
            return
        why = self.verbs.refused_by_job(plotter, verb)
        if why:
            log.info("MQTT: %s of %s refused: %s", verb, plotter, why)
            return
        log.info("MQTT: %s of %s", verb, plotter)
        try:
            if verb == "hold":
                self.verbs.hold(plotter)
            elif verb == "continue":
                self.verbs.go_on(plotter)
            elif verb == "home":
                self._spawn(self.verbs.home(plotter), f"home {plotter}")
        except Refused as exc:
            log.info("MQTT: %s of %s refused: %s", verb, plotter, exc.detail)

    def _spawn(self, work: Any, what: str) -> None:
        async def run() -> None:
            try:
                await work
            except Refused as exc:
                log.info("MQTT: %s refused: %s", what, exc.detail)

        task = asyncio.create_task(run())
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    # ---- the fleet's stops (the web fleet view) -----------------------------------------

    async def stop(self, bridge: str, plotter: str) -> bool:
        """One plotter of the fleet: ours at once, another bridge's through the broker."""
        if bridge == self.settings.bridge:
            if plotter not in self.verbs.plotters:
                raise Refused(404, f"no plotter {plotter!r} on this bridge")
            self.verbs.estop(plotter, "fleet view")
            return True
        return await self.connection.send_now(self.topics.command(plotter, "stop", bridge),
                                              "PRESS")

    async def stop_everything(self) -> bool:
        """Our plotters at once, then every other bridge's through the broker."""
        self.verbs.estop_all("fleet view, STOP EVERYTHING")
        return await self.connection.send_now(self.topics.stop_fleet,
                                              json.dumps({"from": self.settings.bridge}))

    def describe(self) -> dict[str, Any]:
        return {"enabled": True, "bridge": self.settings.bridge, "fleet": self.settings.fleet,
                "connected": self.connection.connected, "bridges": self.fleet.describe(),
                "jobs": self.origin.describe()}


def _is_command(levels: list[str]) -> bool:
    """plotbridge/F/cmd/X, plotbridge/F/B/cmd/X or plotbridge/F/B/plotter/P/cmd/X."""
    return ((len(levels) == 2 and levels[0] == "cmd") or (len(levels) == 3 and levels[1] == "cmd")
            or (len(levels) == 5 and levels[1] == "plotter" and levels[3] == "cmd"))


def _sender(payload: Any) -> str | None:
    try:
        data = json.loads(payload)
    except (TypeError, ValueError):
        return None
    return data.get("from") if isinstance(data, dict) else None
