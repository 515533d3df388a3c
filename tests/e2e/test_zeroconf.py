"""Zeroconf: the server announces itself on the LAN and clients find it by name.

The servers under test listen on 127.0.0.1, so they announce on loopback only
(nothing leaves the machine). Where loopback multicast does not work, the test
checks the exact service records and the registration call instead, and says so.
"""

from __future__ import annotations

import asyncio
import json
import os
import socket
import struct
import subprocess
import sys
import time

import pytest
from plotbridge import __version__, mdns

from tests.fixtures.server import running_server

GROUP = "224.0.0.251"


def loopback_multicast_works() -> bool:
    """A datagram sent to an mDNS-like group on 127.0.0.1 comes back to a member."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as rx, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:  # fmt: skip
        try:
            rx.bind(("0.0.0.0", 0))
            port = rx.getsockname()[1]
            membership = struct.pack("4s4s", socket.inet_aton(GROUP), socket.inet_aton("127.0.0.1"))
            rx.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, membership)
            rx.settimeout(1.0)
            tx.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton("127.0.0.1"))
            tx.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 1)
            tx.sendto(b"probe", (GROUP, port))
            return rx.recv(16) == b"probe"
        except OSError:
            return False


def test_service_records_and_registration_call(monkeypatch, capsys):
    infos = mdns.service_infos("127.0.0.1", 8123, name="studio")
    assert [i.type for i in infos] == ["_plotbridge._tcp.local.", "_http._tcp.local."]
    for info in infos:
        assert info.name == f"plotbridge on studio.{info.type}"
        assert info.server == "studio.local." and info.port == 8123
        assert info.parsed_addresses() == ["127.0.0.1"]
        assert info.properties == {b"path": b"/", b"api": b"/api", b"version": __version__.encode()}

    calls: list[tuple[str, object]] = []

    class Recorder:
        def __init__(self, **kwargs: object) -> None:
            calls.append(("open", kwargs))

        async def async_register_service(self, info, allow_name_change=False) -> None:
            calls.append(("register", (info.type, info.name, info.port, allow_name_change)))

        async def async_close(self) -> None:
            calls.append(("close", None))

    monkeypatch.setattr(mdns, "AsyncZeroconf", Recorder)
    monkeypatch.setattr(socket, "gethostname", lambda: "studio")

    async def serve_briefly() -> None:
        async with mdns.announced("127.0.0.1", 8123):
            for _ in range(100):
                if sum(kind == "register" for kind, _ in calls) == 2:
                    break
                await asyncio.sleep(0.01)
        async with mdns.announced("127.0.0.1", 8124, enabled=False):
            pass

    asyncio.run(serve_briefly())
    assert calls == [
        ("open", {"interfaces": ["127.0.0.1"], "ip_version": mdns.IPVersion.V4Only}),
        ("register", ("_plotbridge._tcp.local.", "plotbridge on studio._plotbridge._tcp.local.",
                      8123, True)),
        ("register", ("_http._tcp.local.", "plotbridge on studio._http._tcp.local.", 8123, True)),
        ("close", None),
    ]  # fmt: skip
    with capsys.disabled():
        print("\nzeroconf: checked the exact service records and the registration call")


@pytest.mark.e2e
def test_a_second_zeroconf_instance_finds_the_server(tmp_path, capsys):
    if not loopback_multicast_works():
        with capsys.disabled():
            print("\nzeroconf: this machine cannot multicast on loopback; the browse is not "
                  "possible here, the records and the registration call are checked by "
                  "test_service_records_and_registration_call")  # fmt: skip
        assert mdns.service_infos("127.0.0.1", 1)[0].parsed_addresses() == ["127.0.0.1"]
        return
    link = ["--virtual", "--sim-speed", "0"]
    with running_server(tmp_path / "data", link, ["--zeroconf"]) as server:
        found: list[mdns.Found] = []
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and not found:
            found = [f for f in mdns.discover(3.0, ["127.0.0.1"]) if f.port == server.port]
        assert found, f"no announcement of port {server.port} seen:\n{server.log()}"
        assert found[0].url == server.url and found[0].properties["path"] == "/"
        assert found[0].name.startswith("plotbridge on ")
        assert "announced plotbridge on" in server.log()

        # `plotbridge status` with no URL finds it the same way.
        env = {k: v for k, v in os.environ.items() if k not in ("PLOTBRIDGE_URL",
                                                                 "PLOTBRIDGE_SERVER")}  # fmt: skip
        env.update(PLOTBRIDGE_TOKEN=server.token, PLOTBRIDGE_MDNS_INTERFACE="127.0.0.1")
        status = subprocess.run([sys.executable, "-m", "plotbridge", "status", "--json"], env=env,
                                capture_output=True, text=True, timeout=60)  # fmt: skip
        assert status.returncode == 0, status.stderr
        assert json.loads(status.stdout)["url"] == server.url
    with capsys.disabled():
        print("\nzeroconf: a second zeroconf instance browsed loopback and found the server")


@pytest.mark.e2e
def test_no_zeroconf_announces_nothing(tmp_path):
    with running_server(tmp_path / "data", ["--virtual", "--sim-speed", "0"]) as server:
        if loopback_multicast_works():
            assert not [f for f in mdns.discover(2.0, ["127.0.0.1"]) if f.port == server.port]
        assert server.client.get("/api/health").status_code == 200
        assert "announced" not in server.log()
