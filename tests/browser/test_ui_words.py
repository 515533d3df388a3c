"""Human words on the page (web/js/words.js, run in Chromium): every job and machine state,
every error and alarm number of GRBL's tables (../shared/grbl/) has a text, and a raw
`error:N` in a message is told in words."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from tests.fixtures.pages import run

pytestmark = pytest.mark.browser

REPO = Path(__file__).resolve().parents[2]
JOB_STATES = ["queued", "waiting", "running", "paused", "pen_change", "done", "failed",
              "cancelled", "stopped", "interrupted"]  # fmt: skip
MACHINE_STATES = ["Idle", "Run", "Hold", "Jog", "Alarm", "Door", "Check", "Home", "Sleep"]


def grbl_codes(name: str) -> list[int]:
    for base in (REPO.parent / "shared" / "grbl", Path("/work/shared/grbl")):
        if base.is_dir():
            with open(base / name, newline="") as f:
                return [int(row[0]) for row in list(csv.reader(f))[1:]]
    raise AssertionError("GRBL's code tables not found beside the repository (../shared/grbl)")


def test_every_state_error_and_alarm_has_words(modules):
    errors, alarms = grbl_codes("error_codes_en_US.csv"), grbl_codes("alarm_codes_en_US.csv")
    got = run(modules, f"""
        const jobs = {json.dumps(JOB_STATES)}.map((s) => m.jobStateText(s));
        const machines = {json.dumps(MACHINE_STATES)}.map((s) => m.machineStateText(s));
        return {{
          jobs, machines,
          errors: {json.dumps(errors)}.map((n) => m.ERRORS[n] || null),
          alarms: {json.dumps(alarms)}.map((n) => m.ALARMS[n] || null),
          said: m.errorText("Try $61: the board refused 'M3' (409): error:9"),
          alarm: m.errorText("ALARM:1"),
        }};
    """)
    assert all(text and "_" not in text for text in got["jobs"]), got["jobs"]
    assert got["jobs"][JOB_STATES.index("pen_change")] == "waiting for a pen"
    assert all(text and text[0].islower() for text in got["machines"]), got["machines"]
    assert None not in got["errors"] and None not in got["alarms"]
    assert "error:9" not in got["said"] and "locked by an alarm" in got["said"]
    assert got["alarm"].startswith("alarm: a limit switch was hit")
