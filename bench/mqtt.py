"""MQTT: STOP latency from the broker, telemetry rate and server CPU per plotter.

Starts a Mosquitto (tests/fixtures/mosquitto.py: users, ACL, free port) and
`plotbridge serve --virtual 4 --mqtt ...` (the real firmware in the simulator at real
time). Then, as Home Assistant would, presses a plotter's discovered STOP button:
`--runs` times with one plotter plotting ("idle": the other three idle) and `--runs`
times with all four streaming; then the same through REST (the page's STOP), as the
baseline the machine's load allows. Latency is the simulator's last step
(`last_step_monotonic`, the same clock as time.monotonic()) minus the moment the
message was handed to the client library; also the time until the board reports Alarm
(GET .../machine, polled every 5 ms). While the four stream, it counts state messages
per plotter per second and the server's CPU (share of one core), per plotter.
Targets: STOP within 50 ms (p99) of the message; telemetry <= 2 messages/s per plotter.

    .venv/bin/python bench/mqtt.py [--runs 20] [--seconds 10]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.fixtures.mosquitto import Broker
from tests.fixtures.mqtt_bridges import discovered, mqtt_args
from tests.fixtures.server import ServerProcess

PLOTTERS = [f"plotter{n}" for n in range(1, 5)]


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def zigzag(rows: int = 400) -> str:
    lines = ["G21", "G90", "M5", "G0 X20 Y20", "M3"]
    for i in range(rows):
        x = 280 if i % 2 == 0 else 20
        lines.append(f"G1 X{x} Y{20 + (i * 1.5) % 180:.3f} F3000")
    return "\n".join([*lines, "M5"]) + "\n"


class Bench:
    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        root = Path(tempfile.mkdtemp(prefix="pb-mqtt-"))
        self.broker = Broker(root / "broker")
        self.server = ServerProcess(root / "data", ["--virtual", "4", "--sim-speed", "1"],
                                    mqtt_args(self.broker, "bench"))  # fmt: skip
        self.jobs: dict[str, str] = {}

    def machine(self, name: str) -> dict:
        return self.server.client.get(f"/api/plotters/{name}/machine").json()

    def trace(self, name: str) -> dict:
        return self.server.client.get(f"/api/plotters/{name}/sim/trace").json()

    def ready(self, name: str) -> None:
        if self.machine(name)["state"] == "Alarm":
            self.server.client.post(f"/api/plotters/{name}/machine/unlock")
        self.server.wait_plotter(name, lambda m: m["state"] == "Idle", 30)

    def plot(self, name: str) -> None:
        self.ready(name)
        answer = self.server.client.post("/api/jobs", files={"file": ("z.gcode", zigzag())},
                                         data={"plotter": name, "start": "true"})  # fmt: skip
        job = answer.json()
        assert answer.status_code == 201 and job["state"] == "running", answer.text
        self.jobs[name] = job["id"]

    def moving(self, name: str) -> None:
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            first = self.trace(name)
            time.sleep(0.05)
            second = self.trace(name)
            if first["pen"] == second["pen"] == "down" and first["steps"] != second["steps"]:
                return
        raise RuntimeError(f"{name} does not draw")

    def stop_once(self, listener, topic: str | None, name: str) -> tuple[float, float]:
        """One STOP through the broker (or, with no topic, through REST for comparison)."""
        self.moving(name)
        sent = time.monotonic()
        if topic is None:
            self.server.client.post(f"/api/plotters/{name}/machine/estop")
        else:
            listener.client.publish(topic, "PRESS", qos=1)
        alarm = None
        while time.monotonic() - sent < 5:
            if self.machine(name)["state"] == "Alarm":
                alarm = time.monotonic() - sent
                break
            time.sleep(0.005)
        time.sleep(0.4)
        before = self.trace(name)
        time.sleep(0.2)
        after = self.trace(name)
        if before["steps"] != after["steps"]:
            raise RuntimeError(f"{name} still steps 0.4 s after the MQTT STOP")
        if alarm is None:
            raise RuntimeError(f"{name} not in Alarm 5 s after the MQTT STOP")
        return after["last_step_monotonic"] - sent, alarm

    def series(self, listener, configs: dict | None, streaming: bool) -> dict:
        steps, alarms = [], []
        for run in range(self.args.runs):
            name = PLOTTERS[run % 4]
            for other in PLOTTERS if streaming else [name]:
                if self.machine(other)["state"] != "Run":
                    self.plot(other)
            topic = configs[f"{name}_stop"]["command_topic"] if configs else None
            step, alarm = self.stop_once(listener, topic, name)
            steps.append(step * 1000)
            alarms.append(alarm * 1000)
        return {"last_step_ms": summary(steps), "alarm_seen_ms": summary(alarms)}

    def load(self, listener) -> dict:
        for name in PLOTTERS:
            if self.machine(name)["state"] != "Run":
                self.plot(name)
        for name in PLOTTERS:
            self.moving(name)
        assert self.server.proc is not None
        pid = self.server.proc.pid
        count0 = len(listener.messages)
        c0, t0 = cpu_seconds(pid), time.monotonic()
        time.sleep(self.args.seconds)
        c1, t1 = cpu_seconds(pid), time.monotonic()
        states = [m for m in listener.messages[count0:] if m[1].endswith("/state")]
        seconds = t1 - t0
        for name in PLOTTERS:
            self.server.client.post(f"/api/jobs/{self.jobs[name]}/cancel")
        cpu = 100 * (c1 - c0) / seconds
        return {"state_messages_per_s_per_plotter": round(len(states) / seconds / 4, 2),
                "server_cpu_percent_of_one_core": round(cpu, 1),
                "server_cpu_percent_per_plotter": round(cpu / 4, 1)}

    def run(self) -> dict:
        self.broker.start()
        self.server.start()
        listener = self.broker.listener("homeassistant", ("homeassistant/#", "plotbridge/#"))
        try:
            deadline = time.monotonic() + 30
            configs = discovered(listener, "bench")
            while len(configs) < 4 * 13 + 2 and time.monotonic() < deadline:
                time.sleep(0.1)
                configs = discovered(listener, "bench")
            for name in PLOTTERS:
                self.server.wait_plotter(name, lambda m: m["connected"], 30)
                self.server.client.post(f"/api/plotters/{name}/machine/home", timeout=130)
            return {"idle": self.series(listener, configs, streaming=False),
                    "four_streaming": self.series(listener, configs, streaming=True),
                    "rest_four_streaming": self.series(listener, None, streaming=True),
                    "telemetry": self.load(listener), "runs": self.args.runs}
        finally:
            listener.close()
            self.server.close()
            self.broker.stop()


def summary(values: list[float]) -> dict:
    ordered = sorted(values)
    p99 = ordered[min(len(ordered) - 1, round(0.99 * (len(ordered) - 1)))]
    return {"median": round(statistics.median(ordered), 1), "p99": round(p99, 1),
            "max": round(ordered[-1], 1)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--seconds", type=float, default=10.0)
    result = Bench(parser.parse_args()).run()
    print(json.dumps(result, indent=2))
    worst = max(result["idle"]["last_step_ms"]["p99"],
                result["four_streaming"]["last_step_ms"]["p99"])
    print(f"MQTT STOP p99 {worst:.1f} ms (target 50 ms): {'MET' if worst <= 50 else 'NOT MET'}")


if __name__ == "__main__":
    main()
