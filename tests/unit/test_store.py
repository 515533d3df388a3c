"""Job store: SQLite in WAL mode, order and survival across reopen."""

from __future__ import annotations

import sqlite3

from plotbridge.store import JobStore


def job(job_id: str, state: str = "queued") -> dict:
    return {"id": job_id, "name": f"job {job_id}", "state": state, "lines_done": 0}


def test_wal_and_roundtrip(tmp_path):
    store = JobStore(tmp_path / "plotbridge.db")
    assert store.journal_mode() == "wal"
    store.save(job("a"), 0)
    store.save(job("b"), 1)
    store.save({**job("a"), "state": "running", "lines_done": 7}, 0)
    store.close()
    again = JobStore(tmp_path / "plotbridge.db")
    jobs = again.load_all()
    assert [j["id"] for j in jobs] == ["a", "b"]
    assert jobs[0]["state"] == "running" and jobs[0]["lines_done"] == 7


def test_order_and_delete(tmp_path):
    store = JobStore(tmp_path / "plotbridge.db")
    for index, name in enumerate("abc"):
        store.save(job(name), index)
    store.set_order(["c", "a", "b"])
    assert [j["id"] for j in store.load_all()] == ["c", "a", "b"]
    store.delete("a")
    assert [j["id"] for j in store.load_all()] == ["c", "b"]


def test_readable_by_another_connection_while_open(tmp_path):
    store = JobStore(tmp_path / "plotbridge.db")
    store.save(job("a"), 0)
    other = sqlite3.connect(tmp_path / "plotbridge.db")
    assert other.execute("SELECT count(*) FROM jobs").fetchone()[0] == 1
    other.close()
