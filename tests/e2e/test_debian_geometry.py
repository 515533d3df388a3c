"""The importer on Debian 12's own shapely (1.8) and numpy (1.24), which the venv takes on
armhf (requirements-nowheel.txt), draws what it draws on the pinned shapely 2 and numpy 2.

A venv made by Debian's python3 with --system-site-packages (python3-shapely and
python3-numpy: scripts/setup-system test) gets only the importer's other pins, offline from
the wheelhouse of `make setup-test`. tests/fixtures/geometry_dump.py imports the test
drawings there and in the main venv; the strokes must match within a rounding of the
preview. GEOS differs too (Debian's 3.11, the wheel's own), and its line merge may give a
clipped shape's pieces in another order: each drawing's strokes are compared as a set."""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
WHEELHOUSE = ROOT / ".venv" / "wheelhouse"
DEBIAN_PYTHON = "/usr/bin/python3"
DEBIAN_SITE = "/usr/lib/python3/dist-packages/"
IMPORTER_PINS = ("defusedxml", "hershey-fonts", "svgelements")   # besides numpy and shapely
TOLERANCE = 2e-3   # mm: the preview's 3 decimals, rounded either way


def pins(names: tuple[str, ...]) -> list[str]:
    text = (ROOT / "requirements.txt").read_text()
    lines = [ln.split("#")[0].strip() for ln in text.splitlines()]
    found = [ln for ln in lines if ln.split("==")[0].lower() in names]
    assert len(found) == len(names), f"requirements.txt pins {found}, not all of {names}"
    return found


def debian_venv(where: Path) -> Path:
    subprocess.run([DEBIAN_PYTHON, "-m", "venv", "--system-site-packages", where], check=True)
    pip = subprocess.run(
        [where / "bin/python", "-m", "pip", "install", "-q", "--disable-pip-version-check",
         "--no-compile", "--no-index", "--find-links", WHEELHOUSE, *pins(IMPORTER_PINS)],
        capture_output=True, text=True, timeout=300)
    assert pip.returncode == 0, pip.stdout + pip.stderr
    return where / "bin/python"


def dump(python: Path | str) -> dict:
    env = {**os.environ, "PYTHONPATH": f"{ROOT}:{ROOT / 'server'}"}
    env.pop("VIRTUAL_ENV", None)
    run = subprocess.run([python, "-m", "tests.fixtures.geometry_dump"], cwd=ROOT, env=env,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


def close(a: list, b: list) -> bool:
    return len(a) == len(b) and all(abs(p - q) <= TOLERANCE for u, v in zip(a, b, strict=True)
                                    for p, q in zip(u, v, strict=True))


def unmatched(ours: list, theirs: list) -> list:
    """The strokes of `ours` with no stroke of `theirs` alike (each used once)."""
    left = list(theirs)
    missing = []
    for stroke in ours:
        k = next((k for k, other in enumerate(left) if close(stroke, other)), None)
        if k is None:
            missing.append(stroke)
        else:
            left.pop(k)
    return missing + left


def test_debians_shapely_and_numpy_draw_the_same_strokes(tmp_path):
    debian = dump(debian_venv(tmp_path / "debian"))
    ours = dump(sys.executable)

    # each side went its own way: Debian's 1.8 one geometry at a time, the pins vectorized
    assert debian["shapely"][1].startswith(DEBIAN_SITE), debian["shapely"]
    assert debian["numpy"][1].startswith(DEBIAN_SITE), debian["numpy"]
    assert debian["shapely"][0].startswith("1.") and debian["numpy"][0].startswith("1.")
    assert not debian["vectorized"] and ours["vectorized"]
    assert ours["shapely"][0].startswith("2.") and ours["numpy"][0].startswith("2.")

    assert debian["drawings"].keys() == ours["drawings"].keys()
    hatched = 0
    for name, mine in ours["drawings"].items():
        other = debian["drawings"][name]
        if "refused" in mine:
            assert other == mine, name
            continue
        assert "strokes" in other, (name, other)
        assert mine["lines"] == other["lines"], name
        assert mine["warnings"] == other["warnings"], name
        assert abs(mine["stats"]["pen_down_mm"] - other["stats"]["pen_down_mm"]) <= TOLERANCE
        assert mine["stats"]["pen_lifts"] == other["stats"]["pen_lifts"], name
        assert unmatched(mine["strokes"], other["strokes"]) == [], name
        hatched += name.endswith(" hatch") and len(mine["strokes"]) > 10
    assert hatched >= 2     # the hatch fills drew (the stars, the holes)
