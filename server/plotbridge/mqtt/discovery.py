"""Home Assistant MQTT discovery: each plotter a device (its bridge the `via_device`) whose
entities read the plotter's retained state topic; the bridge a device with STOP ALL.

Config topics are PREFIX/COMPONENT/plotbridge_FLEET_BRIDGE/OBJECT/config, one node per
bridge, so the bridge can find (and remove) every config it ever left on the broker.
"""

from __future__ import annotations

import json
from typing import Any

from plotbridge import __version__
from plotbridge.mqtt.topics import Topics

PRESS = "PRESS"

# key: (component, name, extra config) for the sensors reading the state topic
SENSORS: dict[str, tuple[str, str, dict[str, Any]]] = {
    "machine_state": ("sensor", "Machine state", {"icon": "mdi:state-machine"}),
    "job": ("sensor", "Job", {"icon": "mdi:file-document-outline"}),
    "job_state": ("sensor", "Job state", {"icon": "mdi:progress-clock"}),
    "progress": ("sensor", "Progress", {"unit_of_measurement": "%",
                                        "state_class": "measurement", "icon": "mdi:percent"}),
    "time_left": ("sensor", "Time left", {"device_class": "duration",
                                          "unit_of_measurement": "s"}),
    "drawn": ("sensor", "Pen-down distance", {"device_class": "distance",
                                              "unit_of_measurement": "m"}),
    "pen_prompt": ("sensor", "Pen change", {"icon": "mdi:pen"}),
    "connected": ("binary_sensor", "Connected", {"device_class": "connectivity",
                                                 "payload_on": "ON", "payload_off": "OFF"}),
}  # fmt: skip
TEMPLATES = {
    "machine_state": "{{ value_json.state }}",
    "job": "{{ value_json.job }}",
    "job_state": "{{ value_json.job_state }}",
    "progress": "{{ value_json.progress }}",
    "time_left": "{{ value_json.time_left }}",
    "drawn": "{{ value_json.drawn_m }}",
    "pen_prompt": "{{ value_json.pen_prompt }}",
    "connected": "{{ 'ON' if value_json.connected else 'OFF' }}",
}
BUTTONS = {"stop": ("STOP", "mdi:stop-circle"), "hold": ("Hold", "mdi:pause"),
           "continue": ("Continue", "mdi:play"), "home": ("Home", "mdi:home")}


class Discovery:
    def __init__(self, topics: Topics, prefix: str, url: str) -> None:
        self.topics = topics
        self.prefix = prefix
        self.url = url
        self.node = f"plotbridge_{topics.fleet}_{topics.bridge}"

    @property
    def our_configs(self) -> str:
        """The subscription that finds every config this bridge left on the broker."""
        return f"{self.prefix}/+/{self.node}/+/config"

    def topic(self, component: str, object_id: str) -> str:
        return f"{self.prefix}/{component}/{self.node}/{object_id}/config"

    def _availability(self) -> dict[str, Any]:
        return {"availability_topic": self.topics.status(), "payload_available": "online",
                "payload_not_available": "offline"}

    def bridge_device(self) -> dict[str, Any]:
        return {"identifiers": [self.node], "name": f"plotbridge {self.topics.bridge}",
                "manufacturer": "plotbridge", "model": "bridge", "sw_version": __version__,
                "configuration_url": self.url}

    def plotter_device(self, plotter: str) -> dict[str, Any]:
        return {"identifiers": [f"{self.node}_{plotter}"], "name": plotter,
                "manufacturer": "plotbridge", "model": "pen plotter", "via_device": self.node,
                "configuration_url": self.url}

    def configs(self, plotters: list[str]) -> dict[str, str]:
        """Every config topic this bridge publishes, and its JSON payload."""
        out: dict[str, str] = {}
        for plotter in plotters:
            device = self.plotter_device(plotter)
            for key, (component, name, extra) in SENSORS.items():
                out[self.topic(component, f"{plotter}_{key}")] = self._dump({
                    "name": name, "unique_id": f"{self.node}_{plotter}_{key}",
                    "state_topic": self.topics.state(plotter),
                    "value_template": TEMPLATES[key], "device": device, **extra,
                })  # fmt: skip
            out[self.topic("event", f"{plotter}_pen_change")] = self._dump({
                "name": "Pen change request", "unique_id": f"{self.node}_{plotter}_pen_change",
                "state_topic": self.topics.event(plotter), "event_types": ["pen_change"],
                "device": device, "icon": "mdi:pen",
            })  # fmt: skip
            for verb, (name, icon) in BUTTONS.items():
                out[self.topic("button", f"{plotter}_{verb}")] = self._dump({
                    "name": name, "unique_id": f"{self.node}_{plotter}_{verb}",
                    "command_topic": self.topics.command(plotter, verb),
                    "payload_press": PRESS, "device": device, "icon": icon,
                })  # fmt: skip
        out[self.topic("button", "stop_all")] = self._dump({
            "name": "STOP ALL", "unique_id": f"{self.node}_stop_all",
            "command_topic": self.topics.stop_bridge(), "payload_press": PRESS,
            "device": self.bridge_device(), "icon": "mdi:stop-circle",
        })  # fmt: skip
        out[self.topic("binary_sensor", "online")] = json.dumps({
            "name": "Online", "unique_id": f"{self.node}_online",
            "state_topic": self.topics.status(), "payload_on": "online",
            "payload_off": "offline", "device_class": "connectivity",
            "device": self.bridge_device(),
        })  # the bridge's own status, so no availability (it would hide "offline")
        return out

    def _dump(self, config: dict[str, Any]) -> str:
        return json.dumps({**config, **self._availability()})
