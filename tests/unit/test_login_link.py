"""The one-time login link the server and `plotbridge token` print: a name a phone on the
LAN can open (the LAN address, NAME.local), the port the server really listens on, and a
code that logs in once (never the token in a URL)."""

from __future__ import annotations

import re
import socket

from plotbridge import cli, mdns
from plotbridge.people import cli as people_cli
from plotbridge.people.store import PeopleStore

TOKEN = "a-token-of-enough-length-0123"


def test_listening_everywhere_links_by_lan_address_and_zeroconf_name(monkeypatch):
    monkeypatch.setattr(mdns, "machine_addresses", lambda: ["fe80::1", "192.168.1.20"])
    monkeypatch.setattr(socket, "gethostname", lambda: "studio.example")
    assert people_cli.login_hosts("0.0.0.0") == ["192.168.1.20", "studio.local"]
    monkeypatch.setattr(mdns, "machine_addresses", lambda: [])
    assert people_cli.login_hosts("::") == ["studio.local"]  # no LAN address: the zeroconf name
    assert people_cli.login_hosts("10.0.0.5") == ["10.0.0.5"]  # one address: that one


def codes(out: str, port: int) -> list[str]:
    return re.findall(rf":{port}/login\.html#([A-Za-z0-9_-]+)", out)


def test_print_login_prints_a_one_time_link_by_each_name(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(mdns, "machine_addresses", lambda: ["192.168.1.20"])
    monkeypatch.setattr(socket, "gethostname", lambda: "studio")
    cli.print_login("0.0.0.0", 8123, tmp_path)
    out = capsys.readouterr().out
    found = codes(out, 8123)
    assert "open http://192.168.1.20:8123/login.html#" in out
    assert "or http://studio.local:8123/login.html#" in out
    assert len(found) == 2 and found[0] == found[1]  # one code: whichever name is opened
    store = PeopleStore(tmp_path / people_cli.DB_FILE)
    try:
        assert store.use_link(found[0]) == ("token", "token")  # the token's admin, once
        assert store.use_link(found[0]) is None
    finally:
        store.close()


def test_token_command_links_to_the_running_servers_port(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(mdns, "machine_addresses", lambda: ["192.168.1.20"])
    monkeypatch.delenv("PLOTBRIDGE_PORT", raising=False)
    (tmp_path / "token").write_text(TOKEN + "\n")
    assert cli.main(["token", "--data-dir", str(tmp_path)]) == 0
    assert codes(capsys.readouterr().out, 8000)  # no server has run here: the default
    (tmp_path / cli.LISTEN_FILE).write_text("0.0.0.0 8765\n")  # what `serve` writes
    assert cli.main(["token", "--data-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "http://192.168.1.20:8765/login.html#" in out and TOKEN not in out
    assert cli.main(["token", "--data-dir", str(tmp_path), "--port", "9000"]) == 0
    assert codes(capsys.readouterr().out, 9000)
