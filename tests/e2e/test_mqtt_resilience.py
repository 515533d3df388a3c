"""End to end: a broker that is down, refuses our credentials, restarts mid-job or is
flooded with retained garbage changes nothing on the LAN side: jobs finish, STOP from the
page stays within its bound, and the log says what is wrong once, not per message."""

from __future__ import annotations

import threading
import time

import pytest

from tests.fixtures.drawings import drawing
from tests.fixtures.mosquitto import Broker
from tests.fixtures.mqtt_bridges import bridge_server, mqtt_args
from tests.fixtures.server import ServerProcess
from tests.fixtures.trace import rest_stop_mid_stroke
from tests.fixtures.waits import wait_until

pytestmark = pytest.mark.e2e


def plot_one(server: ServerProcess) -> dict:
    server.home()
    job = server.submit(drawing(circles=2))
    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    return done


def log_count(server: ServerProcess, text: str) -> int:
    return server.log_path.read_text(errors="replace").count(text)


def test_broker_down_then_up(plotter, tmp_path):
    broker = Broker(tmp_path / "broker")  # configured, not started: nothing listens yet
    server = ServerProcess(tmp_path / "data", ["--serial", str(plotter.port)],
                           mqtt_args(broker, "A"))  # fmt: skip
    server.start()
    try:
        wait_until(lambda: log_count(server, "MQTT: no connection to"), bool, 20,
                   "the broker-down warning")
        plot_one(server)
        time.sleep(3)  # several reconnection attempts (backoff from 0.5 s)
        assert log_count(server, "MQTT: no connection to") == 1, server.log()
        assert server.client.get("/api/fleet").json()["connected"] is False
        broker.start()
        listener = broker.listener("homeassistant", ("plotbridge/#",))
        try:
            listener.wait(lambda lst: lst.latest.get("plotbridge/default/A/status") == b"online",
                          60, "the bridge connected once the broker is up")
        finally:
            listener.close()
        wait_until(lambda: log_count(server, "connected to"), bool, 5, "the reconnection log")
    finally:
        server.close()
        broker.stop()


def test_broker_refusing_credentials(plotter, broker, tmp_path):
    wrong = tmp_path / "wrong.credentials"
    wrong.write_text("plotbridge:not-the-password\n")
    args = ["--mqtt", broker.url, "--mqtt-credentials", str(wrong), "--mqtt-bridge", "A"]
    server = ServerProcess(tmp_path / "data", ["--serial", str(plotter.port)], args)
    server.start()
    try:
        wait_until(lambda: log_count(server, "refused us"), bool, 20, "the refusal warning")
        plot_one(server)
        assert log_count(server, "refused us") == 1, server.log()
        assert "not-the-password" not in server.log()
    finally:
        server.close()


def test_retained_garbage_flood_changes_nothing(plotter, broker, tmp_path):
    intruder = broker.listener("intruder", ("nothing/here",))
    root = "plotbridge/default"
    garbage = [(f"{root}/A/plotter/plotter1/cmd/stop", "PRESS"),  # retained: never obeyed
               (f"{root}/cmd/stop_all", "{}"), (f"{root}/A/cmd/stop_all", "x"),
               (f"{root}/X/status", "\x00\xff"), (f"{root}/X/info", "[1, 2"),
               (f"{root}/X/plotter/p/state", "{\"state\": 5}"), (f"{root}/jobs/J1", "{}"),
               (f"{root}/A/grant", "garbage"), ("homeassistant/sensor/plotbridge_default_A/"
                                                  "stale_thing/config", "{\"name\": \"old\"}")]
    for topic, payload in garbage:
        intruder.publish(topic, payload, retain=True)
    server = bridge_server(tmp_path / "data", ["--serial", str(plotter.port)], broker, "A")
    stop_flood = threading.Event()

    def flood() -> None:
        n = 0
        while not stop_flood.is_set():
            n += 1
            intruder.client.publish(f"{root}/X{n % 50}/plotter/p{n % 7}/state", b"\x00" * 64,
                                    qos=0, retain=True)  # fmt: skip
            intruder.client.publish(f"{root}/A/claim", b"{not json", qos=0)
            if n % 200 == 0:
                time.sleep(0.01)

    flooding = threading.Thread(target=flood, daemon=True)
    try:
        server.home()
        flooding.start()
        rest_stop_mid_stroke(server, plotter)
        stop_flood.set()
        flooding.join(10)
        plot_one(server)  # and jobs still finish
        # the stale discovery config was removed; the retained command never acted
        ha = broker.listener("homeassistant", ("homeassistant/#",))
        try:
            time.sleep(1)
            assert not ha.matching(lambda t: "stale_thing" in t)
            assert ha.matching(lambda t: "plotter1_stop" in t)
        finally:
            ha.close()
        log = server.log_path.read_text(errors="replace")
        assert log.count("ignoring a retained command") == 1
        assert log.count("ignoring a malformed message") == 1
        assert log.count("ignoring a malformed fleet message on claim") <= 1
        assert "EMERGENCY STOP of plotter1 (MQTT" not in log
    finally:
        stop_flood.set()
        intruder.close()
        server.close()


def test_broker_restarted_mid_job(broker, tmp_path):
    server = bridge_server(tmp_path / "data", ["--virtual", "--sim-speed", "1"], broker, "A")
    listener = broker.listener("homeassistant", ("plotbridge/#",))
    state = "plotbridge/default/A/plotter/plotter1/state"
    try:
        server.home()
        job = server.submit(drawing(circles=3))
        listener.wait(lambda lst: (s := lst.json(state)) and s["job_state"] == "running", 30,
                      "the job running on the broker")
        listener.close()
        broker.restart()  # no persistence: the retained state is gone with it
        listener = broker.listener("homeassistant", ("plotbridge/#",))
        done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
        assert done["state"] == "done", done
        listener.wait(lambda lst: (s := lst.json(state)) and s["job_state"] == "done"
                      and s["progress"] == 100, 30, "telemetry again after the restart")
    finally:
        listener.close()
        server.close()


def test_mqtts_with_the_data_directorys_table(tmp_path):
    broker = Broker(tmp_path / "broker", tls=True)
    broker.start()
    data = tmp_path / "data"
    data.mkdir()
    (data / "plotters.toml").write_text(
        f'[mqtt]\nurl = "{broker.url}"\nca_file = "{broker.ca_file}"\nbridge = "T"\n'
        f'credentials_file = "{broker.credentials()}"\n')
    server = ServerProcess(data, ["--virtual", "--sim-speed", "0"])
    listener = broker.listener("homeassistant", ("plotbridge/#",))
    try:
        server.start()
        listener.wait(lambda lst: lst.latest.get("plotbridge/default/T/status") == b"online",
                      30, "the bridge online over TLS")
        assert "(MQTT 5)" in server.log() and "mqtts://127.0.0.1" in server.log()
    finally:
        listener.close()
        server.close()
        broker.stop()
