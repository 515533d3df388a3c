"""The pen library component: its feed wrapper, the library and store, and its API through
the real app around the scripted fake link (tests/unit/test_api.py)."""

from __future__ import annotations

import asyncio
import math

import pytest
from plotbridge.events import EventHub
from plotbridge.jobs.imports import Importer
from plotbridge.pens import PenFeed, PenLibrary, PenSpec, servo_lines
from plotbridge.pens.feed import move_length
from plotbridge.pens.model import Pen, parse_layer_pens
from plotbridge.program.reader import Command

from tests.fixtures.fake_app import layered_import, make_app, serving, upload
from tests.fixtures.waits import settle


async def numbered(lines: list[str]):
    for number, text in enumerate(lines, 1):
        yield number, text


async def run_feed(feed: PenFeed, lines: list[str]) -> list[tuple[int, str]]:
    return [item async for item in feed.lines(numbered(lines))]


def pen(**fields) -> Pen:
    return Pen(id=1, **{"name": "fine", **fields})


# ---- the feed ---------------------------------------------------------------------------

def test_move_length_of_lines_and_arcs():
    assert move_length(Command.parse("G1 X3 Y4 F100"), 0, 0) == pytest.approx(5.0)
    half = move_length(Command.parse("G2 X20 Y0 I10 J0 F100"), 0, 0)  # clockwise half circle
    assert half == pytest.approx(math.pi * 10)
    quarter = move_length(Command.parse("G3 X10 Y10 I0 J10 F100"), 0, 0)
    assert quarter == pytest.approx(math.pi * 5)
    full = move_length(Command.parse("G2 X0 Y0 I5 J0 F100"), 0, 0)
    assert full == pytest.approx(math.pi * 10)


async def test_feed_caps_draw_feeds_and_counts_acknowledged_pen_down_length():
    counted: list[tuple[int, float]] = []
    feed = PenFeed(pen(speed=1200), 0.0, lambda pen_id, mm: counted.append((pen_id, mm)))
    program = ["G0 X0 Y0", "M3", "G1 X10.000 Y0.000 F3000", "G1 X10.000 Y5.000 F800", "M5",
               "G0 X50 Y50", "G1 X60 Y50 F3000"]  # the last one pen up: not counted
    out = await run_feed(feed, program)
    assert [text for _, text in out][2:4] == ["G1 X10.000 Y0.000 F1200", "G1 X10.000 Y5.000 F800"]
    assert out[6][1] == "G1 X60 Y50 F1200"
    assert feed.sent_mm == pytest.approx(15.0)
    feed.acked(3)
    assert counted == [(1, pytest.approx(10.0))]
    feed.acked(7)
    assert sum(mm for _, mm in counted) == pytest.approx(15.0)
    assert feed.stopped_at is None


async def test_feed_without_a_pen_changes_and_counts_nothing():
    counted = []
    feed = PenFeed(None, 0.0, lambda *args: counted.append(args))
    program = ["M3", "G1 X10 Y0 F3000", "M5"]
    assert [text for _, text in await run_feed(feed, program)] == program
    feed.acked(3)
    assert counted == []


async def test_feed_stops_at_the_first_pen_up_past_the_reink_interval():
    feed = PenFeed(pen(reink_m=0.1), 95.0, lambda *_: None)  # 95 mm drawn, re-ink at 100
    program = ["G0 X0 Y0", "M3", "G1 X4 Y0 F100", "G1 X8 Y0 F100", "G1 X9 Y0 F100", "M5",
               "G0 X20 Y0", "M3", "G1 X30 Y0 F100", "M5"]
    out = await run_feed(feed, program)
    assert out[-1] == (6, "M5") and feed.stopped_at == 6  # the stroke ends, then the pause
    assert feed.position == (9.0, 0.0)
    after = PenFeed(pen(reink_m=0.1), 104.0, lambda *_: None)  # the next pause: at 200 mm
    assert len(await run_feed(after, program)) == len(program) and after.stopped_at is None


def test_servo_lines_only_what_differs():
    spec = PenSpec(name="p", up_us=1100, down_us=1900)
    assert servo_lines(spec, {60: 1100.0, 61: 2000.0}) == ["$61=1900"]
    assert servo_lines(spec, {60: 1100.0, 61: 1900.0}) == []
    assert servo_lines(spec, {}) == ["$60=1100", "$61=1900"]


def test_parse_layer_pens_forms_and_errors():
    assert parse_layer_pens("outline=fine, 2=3,3=") == {"outline": "fine", "2": "3", "3": None}
    assert parse_layer_pens('{"1": 4, "b": null}') == {"1": 4, "b": None}
    for bad in ("outline", "=fine", "{not json", '{"1": [1]}'):
        with pytest.raises(ValueError, match="pens"):
            parse_layer_pens(bad)


# ---- the library --------------------------------------------------------------------------

async def test_library_keeps_pens_and_odometers_across_restarts(tmp_path):
    path = tmp_path / "db.sqlite"
    library = PenLibrary(path, EventHub())
    fine = await library.create(PenSpec(name="Fine 0.3", colour="#FF0000", reink_m=50))
    library.drawn(fine.id, 1234.5)
    library.drawn(fine.id, 0.5)
    library.close()  # writes what the timer had not yet
    again = PenLibrary(path, EventHub())
    kept = again.get("fine 0.3")
    assert kept.colour == "#ff0000" and kept.reink_m == 50
    assert kept.odometer_m == pytest.approx(1.235)
    assert again.odometer_mm(fine.id) == pytest.approx(1235.0)
    await again.reset(fine.id)
    assert again.get(str(fine.id)).odometer_m == 0
    again.close()


async def test_library_flushes_odometers_on_a_timer(tmp_path, monkeypatch):
    monkeypatch.setattr("plotbridge.pens.library.FLUSH_S", 0.01)
    path = tmp_path / "db.sqlite"
    messages = []
    events = EventHub()
    events.subscribe(messages.append)
    library = PenLibrary(path, events)
    marker = await library.create(PenSpec(name="marker"))
    library.drawn(marker.id, 10.0)
    await settle(lambda: any(m["type"] == "pens" and m["pens"][0]["odometer_m"] == 0.01
                             for m in messages))  # fmt: skip
    await asyncio.wrap_future(library.store.submit(lambda: None))  # the writer got there
    reader = PenLibrary(path, EventHub())  # a second view of the same file
    assert reader.odometer_mm(marker.id) == pytest.approx(10.0)
    reader.close()
    library.close()


async def test_library_refuses_duplicates_and_unknown_pens(tmp_path):
    from plotbridge.errors import Refused

    library = PenLibrary(tmp_path / "db.sqlite", EventHub())
    await library.create(PenSpec(name="black"))
    with pytest.raises(Refused) as dup:
        await library.create(PenSpec(name="BLACK"))
    assert dup.value.status == 409
    with pytest.raises(Refused) as missing:
        library.get("blue")
    assert missing.value.status == 404 and "'black'" in str(missing.value.detail)
    for digits_int_refuses in ("²", "①"):  # str.isdigit() says yes, int() says no
        with pytest.raises(Refused) as odd:
            library.get(digits_int_refuses)
        assert odd.value.status == 404
    library.close()


async def test_layers_get_named_matched_or_kept_pens(tmp_path):
    from plotbridge.errors import Refused
    from plotbridge.jobs.model import Layer

    library = PenLibrary(tmp_path / "db.sqlite", EventHub())
    red = await library.create(PenSpec(name="red marker", colour="#ff0000"))
    outline = await library.create(PenSpec(name="outline"))
    layers = [Layer(name=name, colour=colour, first_line=1, last_line=1)
              for name, colour in (("outline", "#000000"), ("b", "#ff0000"), ("c", "#00ff00"))]
    library.assign(layers)
    assert [layer.pen for layer in layers] == [outline.id, red.id, None]
    library.assign(layers, {"c": "RED MARKER", "1": None}, kept=layers)
    assert [layer.pen for layer in layers] == [None, red.id, red.id]
    for wanted, word in (({"9": "outline"}, "no layer '9'"), ({"b": "blue"}, "no pen 'blue'")):
        with pytest.raises(Refused) as refused:
            library.assign(layers, wanted)
        assert refused.value.status == 422 and word in refused.value.detail
    assert [layer.pen for layer in layers] == [None, red.id, red.id]  # nothing changed
    library.close()


# ---- the API --------------------------------------------------------------------------------

async def test_pens_api_crud_and_clear_errors(tmp_path, monkeypatch):
    app, _link = make_app(tmp_path)
    async with serving(app) as client:
        made = await client.post("/api/pens", json={"name": "fine", "colour": "#000000",
                                                    "up_us": 1200, "down_us": 1800,
                                                    "speed": 1500, "reink_m": 80})  # fmt: skip
        assert made.status_code == 201, made.text
        pen_id = made.json()["id"]
        assert made.json()["odometer_m"] == 0
        bad = await client.post("/api/pens", json={"name": "x", "down_us": 3000})
        assert bad.status_code == 422 and bad.json()["detail"][0]["loc"] == ["body", "down_us"]
        bad = await client.post("/api/pens", json={"name": "x", "colour": "red"})
        assert bad.status_code == 422 and bad.json()["detail"][0]["loc"] == ["body", "colour"]
        assert (await client.post("/api/pens", json={"name": "FINE"})).status_code == 409
        changed = await client.patch(f"/api/pens/{pen_id}", json={"speed": None, "name": "f2"})
        assert changed.status_code == 200 and changed.json()["speed"] is None
        assert (await client.patch("/api/pens/f2", json={"up_us": None})).status_code == 422
        assert (await client.get("/api/pens/f2")).json()["id"] == pen_id
        assert [p["name"] for p in (await client.get("/api/pens")).json()] == ["f2"]
        assert (await client.post("/api/pens/f2/reset")).status_code == 200
        assert (await client.delete(f"/api/pens/{pen_id}")).status_code == 204
        missing = await client.get(f"/api/pens/{pen_id}")
        assert missing.status_code == 404 and "no pen" in missing.json()["detail"]


async def test_try_writes_positions_then_moves_the_servo(tmp_path, monkeypatch):
    app, link = make_app(tmp_path)
    async with serving(app) as client:
        await client.post("/api/pens", json={"name": "fine", "up_us": 1200, "down_us": 1800})
        tried = await client.post("/api/pens/fine/try", json={"down": True})
        assert tried.status_code == 200, tried.text
        assert link.commands == ["$60=1200", "$61=1800", "M3"]


async def test_layers_plot_with_their_pens_odometer_and_reink(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", layered_import)
    app, link = make_app(tmp_path)
    link.auto_ack = True
    async with serving(app) as client:
        for name, up, down in (("a", 1000, 2000), ("thin", 1300, 1700)):
            await client.post("/api/pens", json={"name": name, "up_us": up, "down_us": down,
                                                 "speed": 600, "reink_m": 0.004})  # fmt: skip
        link.settings.update({60: 1000.0, 61: 2000.0})
        queue = app.state.components.queue
        prompts: list[dict] = []
        app.state.components.events.subscribe(
            lambda m: (m.get("transition") or {}).get("to") == "pen_change"
            and prompts.append(m["job"]["pen_change"]))  # fmt: skip
        bad = await upload(client, pens="b=nothing")
        assert bad.status_code == 422 and "no pen 'nothing'" in bad.text
        job = (await upload(client, pens="b=thin,c=thin", start="true")).json()
        assert [layer["pen"] for layer in job["layers"]] == [1, 2, 2]  # "a": by its name
        await settle(lambda: queue.jobs[job["id"]].state == "pen_change")
        prompt = queue.jobs[job["id"]].pen_change
        # "a" passed 4 mm on layer 1's last stroke: one prompt at the boundary says both
        assert prompt["message"] == ("Layer 2 of 3, 'b': load pen 'thin', then continue "
                                     "(pen 'a' is due for re-inking: 0.005 m drawn)")
        assert prompt["pen"] == "thin" and prompt["reason"] == "layer" and prompt["reink"] == "a"
        assert not any(c.startswith("$6") for c in link.commands)  # "a" is what the board has
        assert all("F600" in t for _, t in link.streamed if t.startswith("G1"))
        await client.post(f"/api/jobs/{job['id']}/resume")
        await settle(lambda: queue.jobs[job["id"]].pen_change is not None
                     and queue.jobs[job["id"]].pen_change["layer"] == 3)  # fmt: skip
        assert link.commands[3:5] == ["$60=1300", "$61=1700"]
        assert queue.jobs[job["id"]].pen_change["reink"] == "thin"
        await client.post(f"/api/jobs/{job['id']}/resume")
        # thin passes 8 mm on the job's last stroke: no prompt, the job finishes
        await settle(lambda: queue.jobs[job["id"]].state == "done")
        assert [p["reason"] for p in prompts] == ["layer", "layer"]
        await asyncio.sleep(0)
        odometers = {p["name"]: p["odometer_m"] for p in (await client.get("/api/pens")).json()}
        assert odometers == {"a": pytest.approx(0.005), "thin": pytest.approx(0.010)}
        again = await client.patch(f"/api/jobs/{job['id']}", json={"pens": {"1": "thin"}})
        assert again.status_code == 200 and again.json()["layers"][0]["pen"] == 2


async def test_a_start_plots_only_the_chosen_layers(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", layered_import)
    app, link = make_app(tmp_path)
    link.auto_ack = True
    async with serving(app) as client:
        queue = app.state.components.queue
        job = (await upload(client)).json()
        bad = await client.post(f"/api/jobs/{job['id']}/start", json={"layers": [1, 4]})
        assert bad.status_code == 422 and "layer 4: " in bad.text
        bad = await client.post(f"/api/jobs/{job['id']}/start", json={"layers": []})
        assert bad.status_code == 422
        started = await client.post(f"/api/jobs/{job['id']}/start", json={"layers": [1, 3]})
        assert started.status_code == 200 and started.json()["plot_layers"] == [1, 3]
        await settle(lambda: queue.jobs[job["id"]].state == "pen_change")
        assert queue.jobs[job["id"]].pen_change["layer"] == 3  # layer 2 is skipped
        await client.post(f"/api/jobs/{job['id']}/resume")
        await settle(lambda: queue.jobs[job["id"]].state == "done")
        layers = queue.jobs[job["id"]].layers
        second = range(layers[1].first_line, layers[1].last_line + 1)
        sent = [n for n, _ in link.streamed]
        assert not set(second) & set(sent) and layers[2].last_line in sent


async def test_a_resume_plots_the_layers_chosen_then(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", layered_import)
    app, link = make_app(tmp_path)
    link.auto_ack = True
    async with serving(app) as client:
        queue = app.state.components.queue
        job = (await upload(client, start="true")).json()
        await settle(lambda: queue.jobs[job["id"]].state == "pen_change")
        held = await client.post(f"/api/jobs/{job['id']}/resume", json={"layers": [3]})
        assert held.status_code == 422 and "continues as it is" in held.text
        await client.post("/api/machine/estop")
        await settle(lambda: queue.jobs[job["id"]].state == "stopped")
        link.set_state("Idle")
        path = f"/api/jobs/{job['id']}"
        bad = await client.post(f"{path}/resume", json={"layers": [4]})
        assert bad.status_code == 422 and "layer 4: " in bad.text
        assert queue.jobs[job["id"]].plot_layers is None  # a refused choice changes nothing
        sent = len(link.streamed)
        resumed = await client.post(f"{path}/resume_from",
                                    json={"from": {"layer": 3}, "layers": [3]})  # fmt: skip
        assert resumed.status_code == 200, resumed.text
        assert resumed.json()["plot_layers"] == [3]
        await settle(lambda: queue.jobs[job["id"]].state == "done")
        layers = queue.jobs[job["id"]].layers
        after = [n for n, _ in link.streamed[sent:] if n]  # 0: the preamble
        assert min(after) >= layers[2].first_line and layers[2].last_line in after
