"""The `plotbridge` vpype command end to end: a two-layer vpype document plotted on
the virtual plotter, its layers kept as Inkscape layers with colour and pen width."""

from __future__ import annotations

import os
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

VPYPE = str(Path(sys.executable).with_name("vpype"))
SVG = "{http://www.w3.org/2000/svg}"
INKSCAPE = "{http://www.inkscape.org/namespaces/inkscape}"


def _size(stroke: list[list[float]]) -> tuple[float, float]:
    xs, ys = [p[0] for p in stroke], [p[1] for p in stroke]
    return max(xs) - min(xs), max(ys) - min(ys)


@pytest.mark.e2e
def test_two_layer_document_is_plotted_with_its_layers(server_virtual):
    server_virtual.home()
    command = [
        VPYPE, "rect", "-l", "1", "10mm", "10mm", "30mm", "20mm",
        "circle", "-l", "2", "70mm", "30mm", "10mm",
        "color", "-l", "1", "blue", "color", "-l", "2", "red",
        "penwidth", "-l", "2", "0.5mm", "name", "-l", "2", "red pen",
        "plotbridge", "--url", server_virtual.url, "--name", "two layers", "--start", "--wait",
    ]  # fmt: skip
    env = {**os.environ, "PLOTBRIDGE_TOKEN": server_virtual.token}
    proc = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)  # fmt: skip
    deadline = time.monotonic() + 180
    while proc.poll() is None and time.monotonic() < deadline:
        for job in server_virtual.client.get("/api/jobs").json():
            if job["state"] == "pen_change":  # a pen change between the layers: carry on
                server_virtual.client.post(f"/api/jobs/{job['id']}/resume")
        time.sleep(0.1)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    [job] = server_virtual.client.get("/api/jobs").json()
    assert job["name"] == "two layers" and job["state"] == "done" and job["format"] == "svg"

    # The upload: one Inkscape layer per vpype layer, with its colour and pen width.
    original = next((server_virtual.data_dir / "jobs" / job["id"]).glob("original*"))
    groups = [g for g in ET.parse(original).getroot().iter(f"{SVG}g")
              if g.get(f"{INKSCAPE}groupmode") == "layer"]  # fmt: skip
    assert [(g.get(f"{INKSCAPE}label"), g.get("stroke")) for g in groups] == [
        ("layer 1", "#0000ff"), ("red pen", "#ff0000")]  # fmt: skip
    assert float(groups[1].get("stroke-width")) == pytest.approx(0.5 * 96 / 25.4, abs=1e-3)
    assert [len(g.findall(f"{SVG}path")) for g in groups] == [1, 1]
    if job.get("layers"):  # the job model's layers (the importer splits by Inkscape layer)
        assert [layer.get("colour") for layer in job["layers"]] == ["#0000ff", "#ff0000"], job

    # What the pen drew: the 30 x 20 mm rectangle and the 20 mm circle.
    strokes = server_virtual.client.get("/api/sim/trace").json()["strokes"]
    sizes = sorted(_size(stroke) for stroke in strokes if len(stroke) > 1)
    assert len(sizes) == 2, sizes
    (circle_w, circle_h), (rect_w, rect_h) = sorted(sizes, key=lambda s: s[0])
    assert circle_w == pytest.approx(20, abs=0.3) and circle_h == pytest.approx(20, abs=0.3)
    assert rect_w == pytest.approx(30, abs=0.1) and rect_h == pytest.approx(20, abs=0.1)
