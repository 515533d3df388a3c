"""Checks of the shipping files that cannot run here: no Docker engine, no systemd."""

import fnmatch
import os
import re
import shutil
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


UNIT = "etc/systemd/system/plotbridge.service"
RULES = "etc/udev/rules.d/70-plotbridge.rules"


def install_service(dest: Path, *flags: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "DESTDIR": str(dest)}
    return subprocess.run([ROOT / "scripts/install-service", *flags, ROOT], env=env, check=True,
                          capture_output=True, text=True)


def test_install_service_renders_the_unit(tmp_path):
    install_service(tmp_path)
    unit = (tmp_path / UNIT).read_text()
    assert "@REPO@" not in unit
    assert f"ExecStart={ROOT}/.venv/bin/plotbridge serve" in unit
    assert "User=plotbridge" in unit and "SupplementaryGroups=dialout" in unit
    assert re.search(r"^Restart=on-failure$", unit, re.M)
    assert re.search(r"^After=network-online.target$", unit, re.M)
    assert re.search(r"^MemoryMax=\d+[%KMG]$", unit, re.M)
    assert re.search(r"^StandardOutput=journal$", unit, re.M)
    assert "PLOTBRIDGE_DATA_DIR=/var/lib/plotbridge" in unit
    assert "TOKEN=" not in unit.replace("PLOTBRIDGE_TOKEN_FILE", "")  # no token in the unit
    assert (tmp_path / RULES).read_text() == (ROOT / "deploy/70-plotbridge.rules").read_text()


def test_install_service_twice_then_uninstall(tmp_path):
    install_service(tmp_path)
    first = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    install_service(tmp_path)
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == first
    install_service(tmp_path, "--uninstall")
    assert not (tmp_path / UNIT).exists() and not (tmp_path / RULES).exists()
    install_service(tmp_path, "--uninstall")  # nothing there: still fine


def test_systemd_accepts_the_unit(tmp_path):
    """systemd-analyze (Debian 12's systemd) parses the rendered unit: an unknown setting or
    a bad value is a complaint naming the file, a missing ExecStart binary an error."""
    install_service(tmp_path)
    analyze = shutil.which("systemd-analyze")
    assert analyze, "systemd-analyze is part of Debian's systemd package"
    checked = subprocess.run([analyze, "verify", tmp_path / UNIT], capture_output=True,
                             text=True, timeout=60)
    assert checked.returncode == 0, checked.stderr
    assert "plotbridge.service" not in checked.stderr, checked.stderr


# ---- the udev rules: parsed, and run on the properties of two boards ----------------------

RULE_KEY = re.compile(r'\s*([A-Z]+)(?:\{([^}]*)\})?\s*(==|!=|\+=|=)\s*"([^"]*)"\s*(?:,|$)')
MATCH_KEYS = {"ACTION", "SUBSYSTEM", "SUBSYSTEMS", "KERNEL", "ENV"}
ASSIGN_KEYS = {"SYMLINK", "GROUP", "MODE", "TAG", "GOTO", "LABEL", "IMPORT", "ENV"}


def parse_rules(text: str) -> list[list[tuple[str, str | None, str, str]]]:
    rules = []
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        keys, at = [], 0
        while at < len(line):
            match = RULE_KEY.match(line, at)
            assert match, f"line {number}: cannot parse {line[at:]!r}"
            key, attr, op, value = match.groups()
            allowed = MATCH_KEYS if op in ("==", "!=") else ASSIGN_KEYS
            assert key in allowed, f"line {number}: {key} {op} is not a key these rules use"
            keys.append((key, attr, op, value))
            at = match.end()
        rules.append(keys)
    labels = {v for rule in rules for k, _, _, v in rule if k == "LABEL"}
    gotos = {v for rule in rules for k, _, _, v in rule if k == "GOTO"}
    assert gotos <= labels, f"GOTO without its LABEL: {gotos - labels}"
    return rules


def run_rules(rules, device: dict) -> dict:
    """udev's evaluation, for the keys above: the device's symlinks, tags, group, mode."""
    env = dict(device["env"])
    out: dict = {"SYMLINK": [], "TAG": []}

    def value_of(key, attr):
        return env.get(attr, "") if key == "ENV" else device[key]

    def matches(actual, pattern):
        values = actual if isinstance(actual, list) else [actual]
        return any(fnmatch.fnmatchcase(v, alt) for v in values for alt in pattern.split("|"))

    skip_to = None
    for rule in rules:
        if skip_to is not None:
            if ("LABEL", None, "=", skip_to) in rule:
                skip_to = None
            continue
        tests = [(k, a, op, v) for k, a, op, v in rule if op in ("==", "!=")]
        if not all(matches(value_of(k, a), v) == (op == "==") for k, a, op, v in tests):
            continue
        for key, attr, op, value in rule:
            value = re.sub(r"\$env\{(\w+)\}", lambda m: env.get(m[1], ""), value)
            if key == "GOTO":
                skip_to = value
            elif op == "+=":
                out[key].append(value)
            elif op == "=" and key == "ENV":
                env[attr] = value
            elif op == "=" and key in ("GROUP", "MODE"):
                out[key] = value
    return out


UNO = {"ACTION": "add", "SUBSYSTEM": "tty", "KERNEL": "ttyACM0", "SUBSYSTEMS": ["usb", "pci"],
       "env": {"ID_SERIAL_SHORT": "75833353035351A0E1B1",
               "ID_PATH_TAG": "platform-fd500000_pcie-pci-0000_01_00_0-usb-0_1_3_1_0"}}
CH340 = {"ACTION": "add", "SUBSYSTEM": "tty", "KERNEL": "ttyUSB0",
         "SUBSYSTEMS": ["usb-serial", "usb"],
         "env": {"ID_PATH_TAG": "platform-3f980000_usb-usb-0_1_2_1_0"}}


def test_udev_rules_name_each_board_by_serial_number_and_port():
    rules = parse_rules((ROOT / "deploy/70-plotbridge.rules").read_text())
    uno = run_rules(rules, UNO)
    assert uno["SYMLINK"] == ["plotter/serial-75833353035351A0E1B1",
                              "plotter/port-platform-fd500000_pcie-pci-0000_01_00_0-usb-0_1_3_1_0"]
    assert uno["GROUP"] == "dialout" and "systemd" in uno["TAG"]
    clone = run_rules(rules, CH340)  # no serial number: named by its socket only
    assert clone["SYMLINK"] == ["plotter/port-platform-3f980000_usb-usb-0_1_2_1_0"]


def test_udev_rules_leave_other_devices_alone():
    rules = parse_rules((ROOT / "deploy/70-plotbridge.rules").read_text())
    console = {**UNO, "KERNEL": "ttyS0", "SUBSYSTEMS": ["platform"]}
    assert run_rules(rules, console) == {"SYMLINK": [], "TAG": []}
    removed = {**CH340, "ACTION": "remove"}
    assert run_rules(rules, removed) == {"SYMLINK": [], "TAG": []}


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


def test_pi_check_refuses_an_unknown_architecture():
    """`make pi-check ARCH=...` knows the Raspberry Pi's two Debian architectures."""
    refused = subprocess.run([ROOT / "scripts/pi-check", "i386"], capture_output=True, text=True)
    assert refused.returncode == 2
    assert refused.stderr.strip() == "pi-check: ARCH is arm64 or armhf, not 'i386'"
