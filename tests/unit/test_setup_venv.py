"""scripts/setup-venv: what each architecture's venv gets (the plan), and bad tables refused."""

import importlib.machinery
import importlib.util
import json
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "setup-venv"


def load_script():
    loader = importlib.machinery.SourceFileLoader("setup_venv", str(SCRIPT))
    spec = importlib.util.spec_from_loader("setup_venv", loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def plan(arch: str) -> dict:
    out = subprocess.run([SCRIPT, "--plan", "--arch", arch], capture_output=True, text=True,
                         check=True).stdout
    return json.loads(out)


def pins() -> list[str]:
    lines = (ROOT / "requirements.txt").read_text().splitlines()
    return [ln.split("#")[0].strip() for ln in lines if ln.split("#")[0].strip()]


@pytest.mark.parametrize("arch", ["amd64", "arm64"])
def test_wheel_architectures_get_every_pin(arch):
    todo = plan(arch)
    assert todo["pip"] == pins()
    assert todo["debian"] == {} and todo["dropped"] == {}


def test_armhf_takes_debians_numpy_and_shapely_and_drops_the_speedups():
    todo = plan("armhf")
    by_name = {p.split("==")[0].lower(): p for p in pins()}
    assert todo["debian"] == {by_name["numpy"]: "python3-numpy",
                              by_name["shapely"]: "python3-shapely"}
    assert set(todo["dropped"]) == {by_name["uvloop"], by_name["httptools"], by_name["pyyaml"]}
    assert all(reason.strip() for reason in todo["reasons"].values())
    # everything else at the same pins, in the same order
    left_out = {**todo["debian"], **todo["dropped"]}
    assert todo["pip"] == [p for p in pins() if p not in left_out]


def test_the_server_needs_nothing_armhf_leaves_out():
    """A dropped package is not among plotbridge's declared dependencies (pyproject.toml)."""
    import tomllib

    declared = tomllib.loads((ROOT / "server/pyproject.toml").read_text())["project"]
    names = {d.split(">")[0].split("=")[0].split("[")[0].strip().lower()
             for d in declared["dependencies"]}
    for dropped in plan("armhf")["dropped"]:
        assert dropped.split("==")[0].lower() not in names


@pytest.mark.parametrize(("row", "message"), [
    ("armhf numpy debian:python3-numpy", "expected ARCH PACKAGE INSTEAD REASON"),
    ("armhf numpy compile it, it is slow", "INSTEAD is 'drop' or 'debian:PACKAGE'"),
    ("armhf leftpad drop no wheel", "leftpad is not pinned in requirements.txt"),
])
def test_a_bad_table_row_is_refused_with_its_line(tmp_path, row, message):
    module = load_script()
    table = tmp_path / "requirements-nowheel.txt"
    table.write_text(f"# header\n{row}\n")
    with pytest.raises(module.PlanError) as refused:
        module.read_nowheel(table, "armhf", module.read_pins(ROOT / "requirements.txt"))
    assert str(refused.value).startswith(f"requirements-nowheel.txt line 2: {message}")


def test_an_unpinned_requirement_is_refused(tmp_path):
    module = load_script()
    pinned = tmp_path / "requirements.txt"
    pinned.write_text("numpy==2.4.6\nshapely>=2\n")
    with pytest.raises(module.PlanError, match=r"requirements.txt line 2: expected NAME==VERSION"):
        module.read_pins(pinned)
