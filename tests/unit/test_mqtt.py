"""The MQTT component's pure parts: its settings, discovery configs, telemetry, fleet view."""

from __future__ import annotations

import asyncio
import json

import pytest
from plotbridge.config import ConfigError
from plotbridge.mqtt import settings
from plotbridge.mqtt.connection import Once
from plotbridge.mqtt.discovery import Discovery
from plotbridge.mqtt.fleet import FleetView
from plotbridge.mqtt.telemetry import Telemetry
from plotbridge.mqtt.topics import Topics
from plotbridge.mqtt.verbs import Verbs

from tests.fixtures.fake_app import serve_args


@pytest.fixture(autouse=True)
def no_env(monkeypatch):
    for name in ("MQTT", "MQTT_CREDENTIALS", "MQTT_USERNAME", "MQTT_PASSWORD", "MQTT_FLEET",
                 "MQTT_BRIDGE", "MQTT_ACCEPT"):
        monkeypatch.delenv(f"PLOTBRIDGE_{name}", raising=False)


def read(tmp_path, *args: str):
    return settings.from_args(serve_args(*args), tmp_path, 8000)


def test_off_unless_configured_and_the_command_line(tmp_path):
    assert read(tmp_path) is None
    creds = tmp_path / "creds"
    creds.write_text("bridge:s3cret:with:colons\n")
    s = read(tmp_path, "--mqtt", "mqtts://broker.lan", "--mqtt-credentials", str(creds),
             "--mqtt-bridge", "room-2", "--mqtt-accept", "hold,start")
    assert (s.host, s.port, s.tls) == ("broker.lan", 8883, True)
    assert (s.username, s.password) == ("bridge", "s3cret:with:colons")
    assert s.bridge == "room-2" and s.accept == {"stop", "hold", "start"}
    assert s.allows("stop") and not s.allows("home")
    assert "s3cret" not in repr(s)


def test_the_data_directorys_table_and_the_environment(tmp_path, monkeypatch):
    (tmp_path / "plotters.toml").write_text(
        '[mqtt]\nurl = "mqtt://10.0.0.5:1884"\nfleet = "school"\nusername = "pi"\n'
        'password_file = "mqtt.pw"\naccept = ["stop"]\ndiscovery_prefix = "ha"\n')
    (tmp_path / "mqtt.pw").write_text("pw-from-file\n")
    s = read(tmp_path)
    assert (s.host, s.port, s.fleet, s.username, s.password) == (
        "10.0.0.5", 1884, "school", "pi", "pw-from-file")
    assert s.accept == {"stop"} and s.discovery_prefix == "ha"
    monkeypatch.setenv("PLOTBRIDGE_MQTT_USERNAME", "env-user")
    monkeypatch.setenv("PLOTBRIDGE_MQTT_PASSWORD", "env-pw")
    s = read(tmp_path, "--mqtt", "mqtt://other:1999")
    assert (s.host, s.port, s.username, s.password) == ("other", 1999, "env-user", "env-pw")
    assert s.fleet == "school"  # the rest still from the table


@pytest.mark.parametrize("args, message", [
    (("--mqtt", "mqtt://user:pw@host"), "no user or password in the URL"),
    (("--mqtt", "http://host"), "use mqtt://HOST:PORT"),
    (("--mqtt", "mqtt://host:99999"), "port must be a number"),
    (("--mqtt", "mqtt://host/x"), "no path"),
    (("--mqtt", "mqtt://h", "--mqtt-accept", "stop,launch"), "unknown commands launch"),
    (("--mqtt", "mqtt://h", "--mqtt-bridge", "a/b"), "letters, digits"),
    (("--mqtt", "mqtt://h", "--mqtt-bridge", "jobs"), "taken by the topics"),
    (("--mqtt", "mqtt://h", "--mqtt-credentials", "/nonexistent/creds"), "credentials file"),
])  # fmt: skip
def test_bad_settings_say_what_and_where(tmp_path, args, message):
    with pytest.raises(ConfigError, match=message):
        read(tmp_path, *args)


def test_bad_table_says_where(tmp_path):
    (tmp_path / "plotters.toml").write_text('[mqtt]\nurl = "mqtt://h"\ncolour = 1\n')
    with pytest.raises(ConfigError, match=r"plotters\.toml: \[mqtt\]: unknown keys colour"):
        read(tmp_path)


def test_discovery_configs():
    configs = Discovery(Topics("f", "b1"), "homeassistant", "http://b1:8000/").configs(
        ["left", "right"])
    assert len(configs) == 2 * 13 + 2  # per plotter 8 sensors, an event, 4 buttons
    for topic, text in configs.items():
        prefix, component, node, object_id, last = topic.split("/")
        config = json.loads(text)
        assert (prefix, node, last) == ("homeassistant", "plotbridge_f_b1", "config")
        assert component in ("sensor", "binary_sensor", "button", "event")
        assert config["unique_id"] == f"plotbridge_f_b1_{object_id}"
        assert ("command_topic" in config) == (component == "button")
    stop = json.loads(configs["homeassistant/button/plotbridge_f_b1/left_stop/config"])
    assert stop["command_topic"] == "plotbridge/f/b1/plotter/left/cmd/stop"
    assert stop["device"]["via_device"] == "plotbridge_f_b1"
    assert stop["availability_topic"] == "plotbridge/f/b1/status"


def test_telemetry_follows_jobs_and_sends_a_pen_change_event_once():
    states: list[tuple[str, dict]] = []
    events: list[tuple[str, dict]] = []

    async def run() -> None:
        t = Telemetry(["p1"], lambda p, s: states.append((p, json.loads(s))),
                      lambda p, e: events.append((p, json.loads(e))))
        t.on_event({"type": "machine", "plotter": "p1",
                    "machine": {"state": "Run", "connected": True}})
        job = {"id": "j1", "name": "cat", "plotter": "p1", "state": "running",
               "progress": 0.25, "eta_s": 60.4, "layers": [
                   {"pen_down_mm": 2000, "progress": 0.5}]}
        t.on_event({"type": "job", "job": job})
        pen = {**job, "state": "pen_change", "pen_change": {"message": "put in red",
                                                            "layer": 2}}
        t.on_event({"type": "job", "job": pen})
        t.on_event({"type": "job", "job": pen})
        t.on_event({"type": "job", "job": {**job, "id": "other", "plotter": "p2"}})
        await asyncio.sleep(0.7)  # the throttled update goes out
        t.close()

    asyncio.run(run())
    assert states[0][1]["state"] == "Run"
    last = states[-1][1]
    assert last["job"] == "cat" and last["job_state"] == "pen_change"
    assert last["progress"] == 25.0 and last["time_left"] == 60 and last["drawn_m"] == 1.0
    assert last["pen_prompt"] == "put in red"
    assert events == [("p1", {"event_type": "pen_change", "message": "put in red",
                              "job": "cat", "layer": 2, "colour": None})]
    assert len(states) <= 3  # throttled: not one per message


def test_fleet_view_keeps_valid_messages_and_drops_garbage(caplog):
    view = FleetView(Once())
    view.status("B", b"online")
    view.info("B", b'{"url": "http://b:8000/", "plotters": ["p"]}')
    view.state("B", "p", json.dumps({"state": "Idle", "progress": 0, "job": ""}).encode())
    for junk in (b"\xff", b"[]", b'{"state": 1}', b"x" * 20000):
        view.state("B", "q", junk)
    view.status("C", b"maybe")
    view.info("D", b'{"url": 5}')
    [bridge] = view.describe()
    assert bridge["bridge"] == "B" and bridge["online"] and bridge["url"] == "http://b:8000/"
    assert [p["name"] for p in bridge["plotters"]] == ["p"]
    assert sum("malformed" in r.message for r in caplog.records) == 1
    view.state("B", "p", b"")  # a cleared retained state: the plotter went away
    assert view.describe()[0]["plotters"] == []


def test_hold_and_continue_follow_the_jobs_actions():
    class Job:
        id = "j1"
        actions = ("stop", "continue")

    class Unit:
        job: Job | None = Job()

    class Queue:
        def plotter(self, name: str) -> Unit:
            assert name == "p"
            return Unit()

    verbs = Verbs(Queue(), None, None)  # type: ignore[arg-type]
    assert verbs.refused_by_job("p", "hold") == "p's job j1 allows stop, continue now"
    assert verbs.refused_by_job("p", "continue") is None
    assert verbs.refused_by_job("p", "home") is None
    Unit.job = None  # no job: the machine itself holds
    assert verbs.refused_by_job("p", "hold") is None


def test_mqtt_acts_as_the_bridges_operator_by_the_role_table():
    """Each verb asks the role table as MQTT's operator and is audited under that name;
    what needs more than an operator is refused (403), a STOP never."""
    from plotbridge.access import Role
    from plotbridge.errors import Refused
    from plotbridge.people.access import MQTT
    from plotbridge.people.actor import ACTOR

    audit: list[tuple] = []
    done: list[str] = []

    class Access:
        def audit(self, who, what, target=None, detail=None):
            audit.append((who.who, what, target, detail))

    class Actions:
        def hold_plotter(self, name):
            done.append(f"hold {name} by {ACTOR.get()}")

    class Queue:
        def estop(self, name, source):
            done.append(f"stop {name}")

    verbs = Verbs(Queue(), Actions(), Access())  # type: ignore[arg-type]
    verbs.hold("p")
    verbs.estop("p", "MQTT")
    assert done == [f"hold p by {MQTT.who}", "stop p"]
    assert [(who, what) for who, what, *_ in audit] == [
        (MQTT.who, "MQTT hold"), (MQTT.who, "MQTT stop (MQTT)")]
    assert MQTT.role == Role.operator
    try:
        verbs._as_mqtt("MQTT settings", Role.admin, None)
    except Refused as exc:
        assert exc.status == 403 and "needs admin" in exc.detail
    else:
        raise AssertionError("an admin's verb was not refused to MQTT's operator")
    assert audit[-1][3] == {"refused": 403}
