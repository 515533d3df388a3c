"""Every topic this bridge uses (docs/INTERNALS.md, "MQTT"): the one place that names them.

    plotbridge/FLEET/BRIDGE/status                  online | offline (retained; the last will)
    plotbridge/FLEET/BRIDGE/info                    the bridge: url, plotters (retained)
    plotbridge/FLEET/BRIDGE/plotter/NAME/state      a plotter's state (retained)
    plotbridge/FLEET/BRIDGE/plotter/NAME/event      a pen-change prompt (HA event entity)
    plotbridge/FLEET/BRIDGE/plotter/NAME/cmd/VERB   stop | hold | continue | home
    plotbridge/FLEET/BRIDGE/cmd/stop_all            every plotter of the bridge
    plotbridge/FLEET/cmd/stop_all                   every plotter of the fleet
    plotbridge/FLEET/jobs/ID                        a fleet job on offer (retained while it is)
    plotbridge/FLEET/ORIGIN/claim                   to the origin: a claim, or "taken" (imported)
    plotbridge/FLEET/TAKER/grant                    to the taker: grant (with the file), deny,
                                                    go or revoke
    plotbridge/FLEET/ORIGIN/jobs/ID                 where a fleet job runs, its progress (retained)
"""

from __future__ import annotations

from dataclasses import dataclass

ROOT = "plotbridge"
PLOTTER_VERBS = ("stop", "hold", "continue", "home")


@dataclass(frozen=True)
class Topics:
    fleet: str
    bridge: str

    @property
    def fleet_root(self) -> str:
        return f"{ROOT}/{self.fleet}"

    def base(self, bridge: str | None = None) -> str:
        return f"{self.fleet_root}/{bridge or self.bridge}"

    def status(self, bridge: str | None = None) -> str:
        return f"{self.base(bridge)}/status"

    def info(self, bridge: str | None = None) -> str:
        return f"{self.base(bridge)}/info"

    def state(self, plotter: str, bridge: str | None = None) -> str:
        return f"{self.base(bridge)}/plotter/{plotter}/state"

    def event(self, plotter: str) -> str:
        return f"{self.base()}/plotter/{plotter}/event"

    def command(self, plotter: str, verb: str, bridge: str | None = None) -> str:
        return f"{self.base(bridge)}/plotter/{plotter}/cmd/{verb}"

    def stop_bridge(self, bridge: str | None = None) -> str:
        return f"{self.base(bridge)}/cmd/stop_all"

    @property
    def stop_fleet(self) -> str:
        return f"{self.fleet_root}/cmd/stop_all"

    def offer(self, job: str) -> str:
        return f"{self.fleet_root}/jobs/{job}"

    def claim(self, origin: str) -> str:
        return f"{self.base(origin)}/claim"

    def grant(self, taker: str) -> str:
        return f"{self.base(taker)}/grant"

    def placed(self, job: str, origin: str | None = None) -> str:
        return f"{self.base(origin)}/jobs/{job}"

    def subscriptions(self) -> list[str]:
        """What the bridge listens to: its commands, the fleet's stop, every bridge's
        status, info and plotter states, the fleet's jobs and its own fleet messages."""
        root, own = self.fleet_root, self.base()
        return [f"{own}/plotter/+/cmd/+", f"{own}/cmd/+", f"{root}/cmd/+",
                f"{root}/+/status", f"{root}/+/info", f"{root}/+/plotter/+/state",
                f"{root}/jobs/+", f"{own}/claim", f"{own}/grant", f"{own}/jobs/+"]

    def parse(self, topic: str) -> list[str] | None:
        """The levels after plotbridge/FLEET/, or None for a topic outside the fleet."""
        prefix = self.fleet_root + "/"
        return topic[len(prefix):].split("/") if topic.startswith(prefix) else None
