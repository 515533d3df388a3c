"""End to end: Home Assistant over MQTT. A real Mosquitto (password file, ACL), a real
`plotbridge serve --mqtt`, the real firmware in the simulator; the test reads
`homeassistant/#` and presses buttons as Home Assistant does (user `ha`, whose ACL only
lets it read and send commands)."""

from __future__ import annotations

import json

import pytest

from tests.fixtures.drawings import THREE_LAYERS, square_stroke
from tests.fixtures.mqtt_bridges import PREFIX, bridge_server, discovered, state
from tests.fixtures.trace import assert_stopped, stop_clock

pytestmark = pytest.mark.e2e

SENSORS = {"machine_state", "job", "job_state", "progress", "time_left", "drawn", "pen_prompt"}
BUTTONS = {"stop", "hold", "continue", "home"}


@pytest.fixture
def ha_bridge(broker, plotter, tmp_path):
    server = bridge_server(tmp_path / "data", ["--serial", str(plotter.port)], broker, "A")
    listener = broker.listener("homeassistant", (f"{PREFIX}/#", "plotbridge/#"))
    yield server, listener
    listener.close()
    server.close()


def test_discovery_configs_are_valid_and_complete(ha_bridge):
    server, listener = ha_bridge
    configs = listener.wait(lambda lst: (c := discovered(lst, "A")) and len(c) == 15 and c,
                            20, "the bridge's discovery configs")
    plotter_ids = {f"plotter1_{k}" for k in SENSORS | BUTTONS | {"connected", "pen_change"}}
    assert plotter_ids | {"stop_all", "online"} == set(configs)
    status = "plotbridge/default/A/status"
    for object_id, config in configs.items():
        assert config["unique_id"].endswith(object_id) and config["name"]
        device = config["device"]
        assert device["identifiers"] and device["manufacturer"] == "plotbridge"
        if object_id.startswith("plotter1_"):
            assert device["via_device"] == "plotbridge_default_A"
            assert config["availability_topic"] == status
            assert config["payload_available"] == "online"
            assert config["payload_not_available"] == "offline"
        assert ("command_topic" in config) == (object_id.endswith(tuple(BUTTONS))
                                               or object_id == "stop_all")
    assert configs["plotter1_progress"]["unit_of_measurement"] == "%"
    assert configs["plotter1_time_left"]["device_class"] == "duration"
    assert configs["plotter1_pen_change"]["event_types"] == ["pen_change"]
    listener.wait(lambda lst: lst.latest.get(status) == b"online", 20, "the bridge online")
    server.wait_machine(lambda m: m["connected"], 30)
    now = listener.wait(lambda lst: (s := state(lst, configs["plotter1_machine_state"]))
                        and s["connected"] and s, 10, "the plotter's state")
    assert now["state"] == server.machine()["state"]


def test_stop_button_mid_job_and_progress_entities(ha_bridge, plotter):
    server, listener = ha_bridge
    configs = listener.wait(lambda lst: (c := discovered(lst, "A")) and len(c) == 15 and c,
                            20, "the bridge's discovery configs")
    server.home()
    job = server.submit(square_stroke(laps=3))  # outlasts the waits for MQTT progress
    progress = configs["plotter1_progress"]

    def moving(lst):
        now = state(lst, progress)
        return now if now and now["job_state"] == "running" and now["progress"] > 5 else None

    seen = listener.wait(moving, 60, "progress on the progress entity")
    assert seen["job"] == job["name"] and seen["job_id"] == job["id"]
    assert seen["time_left"] is not None and seen["time_left"] > 0
    assert seen["drawn_m"] > 0
    earlier = seen["progress"]
    later = listener.wait(lambda lst: (s := state(lst, progress)) and s["progress"] > earlier
                          and s, 30, "the progress entity to advance")
    assert later["time_left"] <= seen["time_left"]
    server.wait_drawing(job["id"], 80)
    stop = configs["plotter1_stop"]
    sent = stop_clock(plotter)
    listener.publish(stop["command_topic"], stop["payload_press"])
    assert_stopped(server, plotter, job["id"], sent)
    listener.wait(lambda lst: (s := state(lst, progress)) and s["job_state"] == "stopped"
                  and s["state"] == "Alarm", 10, "the entities to show the stop")


def test_pen_change_prompt_event_and_continue_button(ha_bridge):
    server, listener = ha_bridge
    configs = listener.wait(lambda lst: (c := discovered(lst, "A")) and len(c) == 15 and c,
                            20, "the bridge's discovery configs")
    server.home()
    response = server.client.post("/api/jobs", files={"file": ("layers.svg", THREE_LAYERS)},
                                  data={"start": "true"})  # fmt: skip
    assert response.status_code == 201, response.text
    job = response.json()
    server.wait_pen_change(job["id"], 2)
    prompt = listener.wait(lambda lst: (s := state(lst, configs["plotter1_pen_prompt"]))
                           and s["pen_prompt"] and s, 10, "the pen-change prompt")
    assert prompt["pen_prompt"].startswith("Layer 2 of 3, 'shade'")
    event_topic = configs["plotter1_pen_change"]["state_topic"]
    events = [json.loads(p) for _, t, p, _ in listener.messages if t == event_topic]
    assert [e["event_type"] for e in events] == ["pen_change"]
    assert events[0]["message"] == prompt["pen_prompt"] and events[0]["layer"] == 2
    go_on = configs["plotter1_continue"]
    listener.publish(go_on["command_topic"], go_on["payload_press"])  # Continue
    server.wait_pen_change(job["id"], 3)
    listener.publish(go_on["command_topic"], go_on["payload_press"])
    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    listener.wait(lambda lst: (s := state(lst, configs["plotter1_pen_prompt"]))
                  and s["job_state"] == "done" and s["pen_prompt"] == "", 10,
                  "the prompt cleared")


def test_killed_bridge_shows_unavailable(ha_bridge):
    server, listener = ha_bridge
    listener.wait(lambda lst: lst.latest.get("plotbridge/default/A/status") == b"online", 20,
                  "the bridge online")
    server.kill()
    listener.wait(lambda lst: lst.latest.get("plotbridge/default/A/status") == b"offline", 20,
                  "the last will: offline")


def test_configs_of_a_plotter_that_went_away_are_removed(broker, tmp_path):
    listener = broker.listener("homeassistant", (f"{PREFIX}/#", "plotbridge/#"))
    try:
        server = bridge_server(tmp_path / "data", ["--virtual", "2", "--sim-speed", "0"],
                               broker, "A")
        listener.wait(lambda lst: len(discovered(lst, "A")) == 2 * 13 + 2, 30,
                      "the configs of two plotters")
        listener.wait(lambda lst: lst.json("plotbridge/default/A/plotter/plotter2/state"), 30,
                      "plotter2's state")
        server.stop()
        server.link_args = ["--virtual", "1", "--sim-speed", "0"]
        server.start()
        try:
            gone = listener.wait(lambda lst: (c := discovered(lst, "A")) and len(c) == 15 and c,
                                 30, "plotter2's configs removed")
            assert not any(object_id.startswith("plotter2_") for object_id in gone)
            listener.wait(lambda lst: not lst.json("plotbridge/default/A/plotter/plotter2/state"),
                          10, "plotter2's retained state removed")
        finally:
            server.close()
    finally:
        listener.close()
