"""Job store: SQLite in WAL mode, order and survival across reopen, the schema migration."""

from __future__ import annotations

import json
import sqlite3

from plotbridge.jobs.model import Job
from plotbridge.jobs.progress import follow, plan_of
from plotbridge.jobs.store import SCHEMA_VERSION, JobStore


def job(job_id: str, state: str = "queued", **fields) -> Job:
    return Job(id=job_id, name=f"job {job_id}", state=state, format="gcode", lines_total=10,
               estimate_s=1.0, **fields)  # fmt: skip


def open_store(tmp_path) -> JobStore:
    return JobStore(tmp_path / "plotbridge.db", first_plotter="left")


def test_wal_and_roundtrip_keeps_the_servers_own_fields(tmp_path):
    store = open_store(tmp_path)
    assert store.journal_mode() == "wal"
    store.save(job("a"), 0)
    store.save(job("b"), 1)
    store.save(job("a", "running", lines_done=7, safe_line=3, source="original.svg"), 0).result()
    store.close()
    again = open_store(tmp_path)
    jobs = again.load_all()
    assert [j.id for j in jobs] == ["a", "b"]
    assert jobs[0].state == "running" and jobs[0].lines_done == 7
    assert jobs[0].safe_line == 3 and jobs[0].source == "original.svg"
    assert "safe_line" not in jobs[0].public() and "source" not in jobs[0].public()


def test_layers_keep_their_progress_and_extra_keys(tmp_path):
    layers = [{"name": "a", "colour": "#000000", "first_line": 1, "last_line": 10,
               "pen_down_mm": 5.0, "estimate_s": 2.0, "ink": "fineliner"}]  # fmt: skip
    running = job("a", "running", layers=layers, lines_done=5, timeline=[(10, 2.0)])
    follow(running, None, plan_of(running, None, 0), 6, None)
    store = open_store(tmp_path)
    store.save(running, 0).result()
    store.close()
    (kept,) = open_store(tmp_path).load_all()
    (layer,) = kept.layers
    assert layer.lines_done == 5 and layer.progress == 0.5 and layer.pen_down_mm == 5.0
    assert kept.public()["layers"] == running.public()["layers"]
    assert kept.public()["layers"][0]["ink"] == "fineliner"  # a key the model does not name


def test_order_and_delete(tmp_path):
    store = open_store(tmp_path)
    for index, name in enumerate("abc"):
        store.save(job(name), index)
    store.set_order(["c", "a", "b"]).result()
    assert [j.id for j in store.load_all()] == ["c", "a", "b"]
    store.delete("a").result()
    assert [j.id for j in store.load_all()] == ["c", "b"]


def test_readable_by_another_connection_while_open(tmp_path):
    store = open_store(tmp_path)
    store.save(job("a"), 0).result()
    other = sqlite3.connect(tmp_path / "plotbridge.db")
    assert other.execute("SELECT count(*) FROM jobs").fetchone()[0] == 1
    other.close()


# A data directory as the single-plotter server wrote it (schema 0): its table, and a
# job row exactly as that server's JobManager stored it.
SINGLE_PLOTTER_ROWS = [
    {"id": "0f3a9c1b2d4e", "name": "spiral", "state": "interrupted", "created_at": 1763880000.5,
     "lines_done": 412, "progress": 0.41, "error": "the link to the plotter was lost",
     "placement": {"paper": "A4", "margin": 10.0, "fit": True, "rotate": 0, "scale": 1.0,
                   "dx": 0.0, "dy": 0.0},
     "resume_line": 398, "started_at": 1763880010.0, "finished_at": 1763880090.0,
     "kind": "file", "source": "original.svg", "filename": "spiral.svg",
     "options": {"paper": "A4", "fit": True, "name": "spiral"}, "format": "svg",
     "lines_total": 1000, "estimate_s": 120.0, "eta_s": 70.5,
     "bounds": {"min_x": 10.0, "min_y": 10.0, "max_x": 200.0, "max_y": 287.0},
     "stats": {"pen_down_mm": 1500.0}, "timeline": [[500, 60.0], [1000, 120.0]],
     "safe_line": 398},
    {"id": "77aa00bb11cc", "name": "queued one", "state": "queued", "created_at": 1763880100.0,
     "lines_done": 0, "progress": 0.0, "error": None, "placement": {}, "resume_line": None,
     "started_at": None, "finished_at": None, "kind": "pattern", "source": "grid",
     "filename": "grid", "options": {}, "format": "pattern", "lines_total": 50,
     "estimate_s": 5.0, "eta_s": 5.0,
     "bounds": {"min_x": 0.0, "min_y": 0.0, "max_x": 50.0, "max_y": 50.0},
     "stats": {}, "timeline": [[50, 5.0]]},
]  # fmt: skip


def test_single_plotter_data_dir_migrates_with_jobs_and_history_intact(tmp_path):
    old = sqlite3.connect(tmp_path / "plotbridge.db", isolation_level=None)
    old.execute("PRAGMA journal_mode=WAL")
    old.execute("CREATE TABLE jobs (id TEXT PRIMARY KEY, position INTEGER NOT NULL, "
                "data TEXT NOT NULL)")  # fmt: skip
    for position, row in enumerate(SINGLE_PLOTTER_ROWS):
        old.execute("INSERT INTO jobs VALUES (?, ?, ?)", (row["id"], position, json.dumps(row)))
    old.close()
    store = open_store(tmp_path)
    assert store.version == SCHEMA_VERSION
    interrupted, queued = store.load_all()
    assert interrupted.plotter == "left" and queued.plotter is None  # ran there; not yet
    assert interrupted.resume_line == 398 and interrupted.safe_line == 398
    assert interrupted.timeline == [(500, 60.0), (1000, 120.0)]
    assert interrupted.public()["placement"]["paper"] == "A4"
    assert queued.kind == "pattern" and queued.source == "grid"
    store.close()
    assert [j.plotter for j in open_store(tmp_path).load_all()] == ["left", None]  # once
