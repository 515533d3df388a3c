"""What a power cut cannot take: every commit of the server's SQLite file is synced (WAL,
synchronous=FULL), and an import's folder reaches the disk before it is published."""

import os

from plotbridge.database import connect
from plotbridge.jobs import imports
from plotbridge.jobs.store import SCHEMA, JobStore

FULL = 2  # PRAGMA synchronous


def test_every_connection_is_wal_and_fully_synced(tmp_path):
    db = connect(tmp_path / "plotbridge.db", SCHEMA)
    assert db.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    assert db.execute("PRAGMA synchronous").fetchone()[0] == FULL
    db.close()


def test_the_job_store_commits_synced(tmp_path):
    store = JobStore(tmp_path / "plotbridge.db", "plotter1")
    try:
        assert store._db.execute("PRAGMA synchronous").fetchone()[0] == FULL
    finally:
        store.close()


def test_an_import_is_synced_before_its_folder_is_published(tmp_path, monkeypatch):
    partial = tmp_path / "jobs" / ".abc.partial"
    (partial / "layers").mkdir(parents=True)
    for name in ("original.svg", "program.bin", "layers/1.json"):
        (partial / name).write_text(name)
    events = []
    real_fsync, real_rename = os.fsync, type(partial).rename

    def fsync(fd):
        events.append(("fsync", os.readlink(f"/proc/self/fd/{fd}")))
        real_fsync(fd)

    def rename(self, target):
        events.append(("rename", str(target)))
        return real_rename(self, target)

    monkeypatch.setattr(imports.os, "fsync", fsync)
    monkeypatch.setattr(type(partial), "rename", rename)
    folder = tmp_path / "jobs" / "abc"
    imports._publish(partial, folder)

    renamed = events.index(("rename", str(folder)))
    synced_before = {path for kind, path in events[:renamed] if kind == "fsync"}
    assert synced_before == {str(partial / n) for n in ("original.svg", "program.bin", "layers",
                                                         "layers/1.json")} | {str(partial)}
    assert events[renamed + 1:] == [("fsync", str(tmp_path / "jobs"))]
    assert (folder / "layers/1.json").read_text() == "layers/1.json"
