"""The login link the server and `plotbridge token` print: a name a phone on the LAN can
open (the LAN address, NAME.local), and the port the server really listens on."""

from __future__ import annotations

import socket

from plotbridge import cli, mdns


def test_listening_everywhere_links_by_lan_address_and_zeroconf_name(monkeypatch):
    monkeypatch.setattr(mdns, "machine_addresses", lambda: ["fe80::1", "192.168.1.20"])
    monkeypatch.setattr(socket, "gethostname", lambda: "studio.example")
    assert cli.login_hosts("0.0.0.0") == ["192.168.1.20", "studio.local"]
    monkeypatch.setattr(mdns, "machine_addresses", lambda: [])
    assert cli.login_hosts("::") == ["studio.local"]  # no LAN address: the zeroconf name
    assert cli.login_hosts("10.0.0.5") == ["10.0.0.5"]  # one address: that one


def test_print_login_uses_the_port_given(monkeypatch, capsys):
    monkeypatch.setattr(mdns, "machine_addresses", lambda: ["192.168.1.20"])
    monkeypatch.setattr(socket, "gethostname", lambda: "studio")
    cli.print_login("0.0.0.0", 8123, "tok-en")
    out = capsys.readouterr().out
    assert "open http://192.168.1.20:8123/login?token=tok-en" in out
    assert "or http://studio.local:8123/login?token=tok-en" in out


def test_token_command_links_to_the_running_servers_port(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(mdns, "machine_addresses", lambda: ["192.168.1.20"])
    monkeypatch.delenv("PLOTBRIDGE_PORT", raising=False)
    (tmp_path / "token").write_text("a-token-of-enough-length-0123\n")
    assert cli.main(["token", "--data-dir", str(tmp_path)]) == 0
    assert ":8000/login" in capsys.readouterr().out  # no server has run here: the default
    (tmp_path / cli.LISTEN_FILE).write_text("0.0.0.0 8765\n")  # what `serve` writes
    assert cli.main(["token", "--data-dir", str(tmp_path)]) == 0
    link = "http://192.168.1.20:8765/login?token=a-token-of-enough-length-0123"
    assert link in capsys.readouterr().out
    assert cli.main(["token", "--data-dir", str(tmp_path), "--port", "9000"]) == 0
    assert ":9000/login" in capsys.readouterr().out
