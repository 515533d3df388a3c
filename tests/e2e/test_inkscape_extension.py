"""The Inkscape extension's script, run with inkex as Inkscape runs it, against a real
server: the document goes up with its layers, the estimate or the errors come back."""

from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "integrations" / "inkscape" / "plotbridge_send.py"
INX = SCRIPT.with_suffix(".inx")
FIXTURE = Path(__file__).parent / "data" / "inkscape_two_layers.svg"
INKSCAPE = "{http://www.inkscape.org/namespaces/inkscape}"
EXTENSION = "{http://www.inkscape.org/namespace/inkscape/extension}"


def send(*options: str, svg: Path = FIXTURE) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(SCRIPT), *options, str(svg)], cwd=SCRIPT.parent,
                          capture_output=True, text=True, timeout=120)  # fmt: skip


def test_inx_declares_the_fields_the_script_reads():
    root = ET.parse(INX).getroot()
    params = {p.get("name") for p in root.iter(f"{EXTENSION}param")}
    assert {"server", "token", "paper", "fit", "layers", "start"} <= params
    assert root.find(f".//{EXTENSION}submenu").get("name") == "plotbridge"
    assert root.find(f"{EXTENSION}name").text == "Send to plotter"
    assert root.find(f".//{EXTENSION}command").text == SCRIPT.name


@pytest.mark.e2e
def test_send_uploads_the_document_with_its_layers(server_virtual):
    server_virtual.home()
    done = send(f"--server={server_virtual.url}/", f"--token={server_virtual.token}",
                "--paper=A5-landscape", "--fit=true", "--start=true")  # fmt: skip
    assert done.returncode == 0, done.stderr
    [job] = server_virtual.client.get("/api/jobs").json()
    assert job["name"] == "two-layers.svg" and job["format"] == "svg"
    assert job["placement"]["paper"] == "A5-landscape" and job["placement"]["fit"] is True
    assert f"Job {job['id']} 'two-layers.svg'" in done.stderr
    assert "Estimated plotting time:" in done.stderr
    original = next((server_virtual.data_dir / "jobs" / job["id"]).glob("original*"))
    labels = [g.get(f"{INKSCAPE}label") for g in ET.parse(original).getroot().iter()
              if g.get(f"{INKSCAPE}groupmode") == "layer"]  # fmt: skip
    assert labels == ["Outline", "Red pen"]
    while job["state"] not in ("done", "failed", "stopped"):  # started: it plots both layers
        if job["state"] == "pen_change":
            server_virtual.client.post(f"/api/jobs/{job['id']}/resume")
        job = server_virtual.wait_job(job["id"], ("done", "failed", "stopped", "pen_change"), 120)
    assert job["state"] == "done"
    strokes = server_virtual.client.get("/api/sim/trace").json()["strokes"]
    assert len([s for s in strokes if len(s) > 1]) == 2


@pytest.mark.e2e
def test_send_reports_the_servers_errors(server_virtual, tmp_path):
    wrong = send(f"--server={server_virtual.url}", "--token=not-the-right-token-at-all")
    assert wrong.returncode != 0 and "refused the drawing (401)" in wrong.stderr
    missing = send(f"--server={server_virtual.url}", "--token=")
    assert missing.returncode != 0 and "Enter the server's token" in missing.stderr
    empty = tmp_path / "empty.svg"
    empty.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm"/>')
    nothing = send(f"--server={server_virtual.url}", f"--token={server_virtual.token}", svg=empty)
    assert nothing.returncode != 0 and "refused the drawing (422)" in nothing.stderr
    assert server_virtual.client.get("/api/jobs").json() == []
    nowhere = send("--server=http://127.0.0.1:9", f"--token={server_virtual.token}")
    assert nowhere.returncode != 0 and "Cannot reach http://127.0.0.1:9" in nowhere.stderr
