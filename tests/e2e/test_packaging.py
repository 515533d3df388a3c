"""`pip install ./server` and `pip install "./server[vpype]"` into fresh venvs give a working
`plotbridge` command and vpype plugin: the package declares what it imports.

The installs are offline (`--no-index`) from the wheelhouse `make setup-test` fills with the
pinned wheels, vpype and the build backend (Makefile, WHEELHOUSE), so the test downloads
nothing; the package itself is built from the working tree's server/ (copied, so the build
leaves nothing behind in the checkout). --no-compile: no bytecode for scipy and numpy, which
is most of an install's CPU time and no part of what is tested."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.fixtures.server import ServerProcess

ROOT = Path(__file__).resolve().parents[2]
WHEELHOUSE = ROOT / ".venv" / "wheelhouse"
INSTALL_S = 600  # s: a fresh venv's install on a loaded 2-core machine

pytestmark = [pytest.mark.e2e, pytest.mark.timeout(1200)]

SVG = """<svg xmlns="http://www.w3.org/2000/svg" width="60mm" height="40mm" viewBox="0 0 60 40">
<path d="M 5 5 L 55 5 L 55 35 Z" fill="none" stroke="black"/>
</svg>
"""


def clean_env(home: Path) -> dict[str, str]:
    """The environment of someone without plotbridge settings: no PLOTBRIDGE_*, no venv."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("PLOTBRIDGE_", "VIRTUAL_ENV", "PYTHON"))}
    return {**env, "HOME": str(home)}


def fresh_install(tmp_path: Path, name: str, requirement: str) -> Path:
    """A new venv with `requirement` (relative to a copy of server/) installed; its bin/."""
    source = tmp_path / "server"
    if not source.exists():
        shutil.copytree(ROOT / "server", source, ignore=shutil.ignore_patterns(
            "build", "*.egg-info", "__pycache__"))
    venv = tmp_path / name
    subprocess.run([sys.executable, "-m", "venv", venv], check=True)
    pip = subprocess.run(
        [venv / "bin/python", "-m", "pip", "install", "-q", "--disable-pip-version-check",
         "--no-compile", "--no-index", "--find-links", WHEELHOUSE,
         requirement.replace("./server", str(source))],
        capture_output=True, text=True, timeout=INSTALL_S, env=clean_env(tmp_path))
    assert pip.returncode == 0, pip.stdout + pip.stderr
    return venv / "bin"


def test_server_alone_gives_the_plotbridge_command(tmp_path):
    bin_dir = fresh_install(tmp_path, "plain", "./server")
    helped = subprocess.run([bin_dir / "plotbridge", "--help"], capture_output=True, text=True,
                            env=clean_env(tmp_path), timeout=120)
    assert helped.returncode == 0, helped.stderr
    for verb in ("serve", "submit", "stop", "token"):
        assert verb in helped.stdout
    imported = subprocess.run(
        [bin_dir / "python", "-c", "import plotbridge.client, plotbridge.app, plotbridge.mdns"],
        capture_output=True, text=True, env=clean_env(tmp_path), timeout=120)
    assert imported.returncode == 0, imported.stderr
    assert not (bin_dir / "vpype").exists()  # the extra stays an extra


def test_vpype_extra_lists_the_plugin_and_sends_a_drawing(tmp_path, server_virtual: ServerProcess):
    bin_dir = fresh_install(tmp_path, "with-vpype", "./server[vpype]")
    env = clean_env(tmp_path)
    helped = subprocess.run([bin_dir / "vpype", "--help"], capture_output=True, text=True,
                            env=env, timeout=300)
    assert helped.returncode == 0, helped.stderr
    assert "plotbridge" in helped.stdout.split("Commands:")[-1]
    assert helped.stderr.strip() == "", helped.stderr  # no "could not load plugin" warning

    drawing = tmp_path / "drawing.svg"
    drawing.write_text(SVG)
    sent = subprocess.run(
        [bin_dir / "vpype", "read", drawing, "plotbridge", "--url", server_virtual.url,
         "--token", server_virtual.token, "--name", "from-vpype"],
        capture_output=True, text=True, env=env, timeout=300)
    assert sent.returncode == 0, sent.stdout + sent.stderr
    jobs = server_virtual.client.get("/api/jobs").json()
    [job] = [j for j in jobs if j["name"] == "from-vpype"]
    assert job["state"] == "queued" and job["lines_total"] > 0
    strokes = server_virtual.preview(job["id"])["strokes"]
    assert len(strokes) == 1 and len(strokes[0]) == 4  # the closed triangle
