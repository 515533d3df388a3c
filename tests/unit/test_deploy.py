"""Checks of the shipping files that cannot run here: no Docker engine, no systemd."""

import os
import re
import subprocess
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]


def test_compose_file_describes_the_plotbridge_service():
    compose = yaml.safe_load((ROOT / "docker-compose.yml").read_text())
    assert set(compose) <= {"services", "volumes", "networks", "configs", "secrets", "name"}
    service = compose["services"]["plotbridge"]
    assert (ROOT / service["build"] / "Dockerfile").is_file()
    assert "8000:8000" in service["ports"]
    volume, mount = service["volumes"][0].split(":")
    assert volume in compose["volumes"]
    assert mount == service["environment"]["PLOTBRIDGE_DATA_DIR"]
    for key, value in service["environment"].items():
        assert key.startswith("PLOTBRIDGE_") and isinstance(value, str)


def test_compose_file_documents_the_serial_device_mapping():
    text = (ROOT / "docker-compose.yml").read_text()
    assert re.search(r"^\s*#\s*- /dev/ttyUSB0:/dev/ttyUSB0", text, re.M)
    assert re.search(r"^\s*#\s*- dialout", text, re.M)


def test_dockerfile_installs_like_the_readme():
    dockerfile = (ROOT / "Dockerfile").read_text()
    assert "scripts/setup-system run" in dockerfile
    assert "make setup" in dockerfile
    for copied in re.findall(r"^COPY (\S+) ", dockerfile, re.M):
        assert (ROOT / copied).exists(), copied


def test_install_service_renders_the_unit(tmp_path):
    env = {**os.environ, "DESTDIR": str(tmp_path)}
    subprocess.run([ROOT / "scripts/install-service", ROOT], env=env, check=True,
                   capture_output=True)
    unit = (tmp_path / "etc/systemd/system/plotbridge.service").read_text()
    assert "@REPO@" not in unit
    assert f"ExecStart={ROOT}/.venv/bin/plotbridge serve" in unit
    assert "User=plotbridge" in unit and "SupplementaryGroups=dialout" in unit
    assert "Restart=on-failure" in unit
    assert "PLOTBRIDGE_DATA_DIR=/var/lib/plotbridge" in unit


def test_ci_runs_exactly_the_readme_test_command():
    assert "make test" in (ROOT / ".ci/run").read_text()
    readme = (ROOT / "README.md").read_text()
    assert "make run" in readme and "make test" in readme


def test_shipping_files_raise_the_open_file_limit():
    compose = yaml.safe_load((ROOT / "docker-compose.yml").read_text())
    nofile = compose["services"]["plotbridge"]["ulimits"]["nofile"]
    assert nofile["soft"] >= 4096 and nofile["hard"] >= nofile["soft"]
    unit = (ROOT / "deploy" / "plotbridge.service").read_text()
    assert int(re.search(r"^LimitNOFILE=(\d+)$", unit, re.M).group(1)) >= 4096
    assert re.search(r"^UMask=0077$", unit, re.M)
