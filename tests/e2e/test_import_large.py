"""End to end through a real server: a large generated G-code upload (the importer's
fast path) becomes a job whose line count and bounds are those of the drawing."""

from __future__ import annotations

import random

import pytest

pytestmark = pytest.mark.e2e

STROKES = 100
SEGMENTS = 1000       # per stroke: 100,000 drawing lines


def drawing() -> tuple[str, int, dict]:
    """The G-code, the normalized program's line count and the drawn bounds."""
    rng = random.Random(5)
    out = ["G21", "G90"]
    xs, ys = [], []
    for s in range(STROKES):
        x, y = 20.0 + s, 20.0
        out += [f"G0 X{x:.3f} Y{y:.3f}", "M3"]
        xs.append(x)
        ys.append(y)
        for k in range(SEGMENTS):
            # steps of at least 0.01 mm: every line moves on the 3-decimal grid
            x = min(max(x + rng.choice((-1, 1)) * rng.uniform(0.01, 0.5), 5.0), 195.0)
            y = min(max(y + rng.uniform(0.01, 0.2), 5.0), 195.0) if y < 190 else 20.0
            x, y = round(x, 3), round(y, 3)
            feed = f" F{rng.choice((1500, 3000))}" if k % 50 == 0 else ""
            out.append(f"G1 X{x:.3f} Y{y:.3f}{feed} ; segment {k}")
            xs.append(x)
            ys.append(y)
        out.append("M5")
    # program: G21 G90 M5, then per stroke G0, M3, its lines and M5
    lines = 3 + STROKES * (SEGMENTS + 3)
    bounds = {"min_x": min(xs), "min_y": min(ys), "max_x": max(xs), "max_y": max(ys)}
    return "\n".join(out) + "\n", lines, bounds


def test_large_gcode_upload_becomes_a_job_of_its_lines_and_bounds(server_virtual):
    text, lines, bounds = drawing()
    response = server_virtual.client.post(
        "/api/jobs", files={"file": ("large.gcode", text)}, timeout=300)
    assert response.status_code == 201, response.text
    job = response.json()
    assert job["lines_total"] == lines
    assert job["bounds"] == pytest.approx(bounds, abs=1e-9)
    assert job["stats"]["pen_lifts"] == STROKES
