"""End to end: the pen library on a real `plotbridge serve` and the virtual plotter. A
two-layer drawing with two pens: each layer's servo positions reach the firmware ($60/$61,
seen by the simulator's servo decoder and in `$$`), the odometers match what the layers
drew and survive a restart, and a pen past its re-ink interval pauses the job at a
stroke's end until it is continued."""

from __future__ import annotations

import contextlib
import json
import sqlite3
import threading
import time

import pytest

from tests.fixtures.cli import start_submit
from tests.fixtures.drawings import INK, THREE_LAYERS, layer
from tests.fixtures.trace import assert_parked, assert_same_drawing

pytestmark = pytest.mark.e2e

FINE = {"name": "fineliner 0.3 black", "colour": "#000000", "up_us": 1100, "down_us": 1900,
        "speed": 1200}  # fmt: skip
SERVO_US = 8  # the servo timer ticks 4 µs (firmware/src/servo.c), edges may land one off
MARKER = {"name": "red marker", "colour": "#ff0000", "up_us": 1250, "down_us": 1750}


def two_layers(second: str) -> str:
    return (f'<svg xmlns="http://www.w3.org/2000/svg" {INK} width="100mm" height="40mm" '
            f'viewBox="0 0 100 40">{layer("outline", 5)}{second}</svg>')


def add_pen(server, **fields) -> dict:
    response = server.client.post("/api/pens", json=fields)
    assert response.status_code == 201, response.text
    return response.json()


def odometers(server) -> dict[str, float]:
    return {pen["name"]: pen["odometer_m"] * 1000 for pen in server.client.get("/api/pens").json()}


def stored_odometers(server) -> dict[str, float]:
    """What the database file holds (read by a second connection, as after a crash)."""
    with contextlib.closing(sqlite3.connect(server.data_dir / "plotbridge.db")) as db:
        return dict(db.execute("SELECT name, odometer_mm FROM pens").fetchall())


def board_settings(server) -> dict[str, str]:
    """The firmware's own `$$`, asked through the console."""
    answer = server.client.post("/api/machine/command", json={"line": "$$"})
    assert answer.status_code == 200, answer.text
    return dict(line.split("=", 1) for line in answer.json()["responses"] if "=" in line)


def test_two_layers_two_pens_servo_positions_and_odometer(server, plotter):
    server.home()
    add_pen(server, **FINE)
    add_pen(server, **MARKER)
    plotter.clear()
    drawing = two_layers(layer("shade", 30))
    response = server.client.post(
        "/api/jobs", files={"file": ("pens.svg", drawing)},
        data={"start": "true", "pens": "2=red marker"},
    )  # fmt: skip
    assert response.status_code == 201, response.text
    job = response.json()
    assert [lay["pen"] for lay in job["layers"]] == [1, 2]  # "outline": by colour #000000

    changing = server.wait_pen_change(job["id"], 2)
    assert changing["pen_change"]["message"] == (
        "Layer 2 of 2, 'shade': load pen 'red marker', then continue")
    assert_parked(plotter)
    assert plotter.trace()["pen_us"] == pytest.approx(FINE["up_us"], abs=SERVO_US)  # layer 1
    assert server.client.post(f"/api/jobs/{job['id']}/resume").status_code == 200

    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    assert plotter.trace()["pen_us"] == pytest.approx(MARKER["up_us"], abs=SERVO_US)
    dollars = board_settings(server)
    assert (dollars["$60"], dollars["$61"]) == (str(MARKER["up_us"]), str(MARKER["down_us"]))
    drawn = plotter.trace()["strokes"]
    assert_same_drawing(server.preview(job["id"])["strokes"], drawn)
    seconds = [stroke[-1][2] - stroke[0][2] for stroke in drawn]  # simulated time
    assert seconds[0] >= 60 / (1200 / 60) * 0.99, seconds  # 60 mm at the fineliner's 20 mm/s
    assert seconds[1] < 60 / (1200 / 60) * 0.8, seconds  # the marker: the program's 50 mm/s

    want = {FINE["name"]: done["layers"][0]["pen_down_mm"],
            MARKER["name"]: done["layers"][1]["pen_down_mm"]}  # fmt: skip
    assert all(mm > 50 for mm in want.values()), want
    server.wait_job(job["id"], "done")
    got = odometers(server)
    for name, mm in want.items():
        assert got[name] == pytest.approx(mm, rel=0.005), (name, got, want)
    server.restart()  # a clean stop writes what is left
    assert odometers(server) == pytest.approx(got, rel=1e-6)

    # and without one: once the odometers are on disk (at most a second after the
    # job), a killed server keeps them too
    written = {name: mm * 2 for name, mm in got.items()}
    server.home()  # the restarted server may find the board not yet connected, or in Alarm
    server.client.post(f"/api/jobs/{job['id']}/restart")
    server.wait_pen_change(job["id"], 2)
    server.client.post(f"/api/jobs/{job['id']}/resume")
    server.wait_job(job["id"], ("done",), 120)
    deadline = time.monotonic() + 10
    while stored_odometers(server) != pytest.approx(written, rel=0.005):
        assert time.monotonic() < deadline, (stored_odometers(server), written)
        time.sleep(0.1)
    server.kill()
    server.start()
    assert odometers(server) == pytest.approx(written, rel=0.005)


def test_a_pen_past_its_reink_interval_pauses_at_a_stroke_end(server, plotter):
    server.home()
    add_pen(server, **FINE)
    add_pen(server, **{**MARKER, "reink_m": 0.1})  # a 15 mm square is 60 mm: due in the 2nd
    plotter.clear()
    squares = "".join(f'<rect x="{x}" y="10" width="15" height="15" fill="none" stroke="red"/>'
                      for x in (30, 50, 70))  # fmt: skip
    drawing = two_layers(f'<g inkscape:groupmode="layer" inkscape:label="red">{squares}</g>')
    job = server.client.post("/api/jobs", files={"file": ("reink.svg", drawing)},
                             data={"start": "true", "pens": "red=red marker",
                                   "optimize": "false"}).json()  # fmt: skip
    server.wait_pen_change(job["id"], 2)
    server.client.post(f"/api/jobs/{job['id']}/resume")

    reink = server.wait_job(job["id"], ("pen_change", "done", "failed"), 120)
    while reink["state"] == "pen_change" and reink["pen_change"]["reason"] != "reink":
        reink = server.job(job["id"])
    assert reink["state"] == "pen_change", reink
    prompt = reink["pen_change"]
    assert prompt["layer"] == 2 and prompt["pen"] == "red marker"
    assert prompt["message"].startswith("Re-ink pen 'red marker': 0.1")
    assert_parked(plotter)
    assert len(plotter.trace()["strokes"]) == 3  # the outline and two whole squares

    assert server.client.post(f"/api/jobs/{job['id']}/resume").status_code == 200
    done = server.wait_job(job["id"], ("done", "failed", "stopped", "interrupted"), 120)
    assert done["state"] == "done", done
    drawn = plotter.trace()["strokes"]
    assert len(drawn) == 4  # the third square once, not a part of any again
    assert_same_drawing(server.preview(job["id"])["strokes"], drawn)
    assert odometers(server)["red marker"] == pytest.approx(180, rel=0.005)


def test_submit_picks_layers_and_pens_and_shows_the_prompts(server, plotter, tmp_path):
    server.home()
    add_pen(server, **MARKER)
    plotter.clear()
    drawing = tmp_path / "three.svg"
    drawing.write_text(THREE_LAYERS)
    proc = start_submit(server, str(drawing), "--layers", "1,3", "--pen", "3=red marker",
                  "--pen", "outline=red marker", "--start", "--wait", "--json")  # fmt: skip
    errors: list[str] = []
    reader = threading.Thread(target=lambda: errors.extend(proc.stderr), daemon=True)
    reader.start()
    try:
        deadline = time.monotonic() + 120
        prompt = "Layer 3 of 3, 'detail': load pen 'red marker', then continue"
        while not any(prompt in line for line in errors):  # layer 2 is skipped
            assert proc.poll() is None and time.monotonic() < deadline, errors
            time.sleep(0.05)
        job = server.client.get("/api/jobs").json()[-1]
        assert job["plot_layers"] == [1, 3]
        assert [lay["pen"] for lay in job["layers"]] == [1, None, 1]
        server.client.post(f"/api/jobs/{job['id']}/resume")
        out, _ = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, errors
    assert json.loads(out)["state"] == "done"
    assert len(plotter.trace()["strokes"]) == 2
