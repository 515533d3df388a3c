"""Zeroconf on the LAN: the server announces itself, clients find it by name.

The server registers `_plotbridge._tcp` (for clients) and `_http._tcp` (for
browsers and service lists) with its host name, port and path. A server that
listens on one address announces only there (a loopback server stays on the
machine); one that listens on all addresses announces on every interface.
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import logging
import os
import socket
import time
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import Any

from zeroconf import InterfaceChoice, IPVersion, ServiceBrowser, ServiceInfo, Zeroconf
from zeroconf.asyncio import AsyncServiceInfo, AsyncZeroconf

from plotbridge import __version__

log = logging.getLogger("plotbridge.mdns")

PLOTBRIDGE_TYPE = "_plotbridge._tcp.local."
HTTP_TYPE = "_http._tcp.local."
SERVICE_TYPES = (PLOTBRIDGE_TYPE, HTTP_TYPE)
UNREGISTER_WAIT_S = 3.0
INTERFACE_ENV = "PLOTBRIDGE_MDNS_INTERFACE"  # clients: browse only there (e.g. 127.0.0.1)


def _listen_address(host: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address | None:
    """The one address the server listens on, or None when it listens on all."""
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        return None  # a name: announce everywhere, the name resolves as it may
    return None if address.is_unspecified else address


def machine_addresses() -> list[str]:
    import ifaddr

    found = []
    for adapter in ifaddr.get_adapters():
        for ip in adapter.ips:
            text = ip.ip if isinstance(ip.ip, str) else ip.ip[0]
            address = ipaddress.ip_address(text.split("%")[0])
            if not (address.is_loopback or address.is_link_local):
                found.append(str(address))
    return found


def service_infos(
    host: str, port: int, name: str | None = None, path: str = "/"
) -> list[AsyncServiceInfo]:
    """The records the server registers: one per service type, same name and addresses."""
    hostname = (name or socket.gethostname()).split(".")[0]
    listen = _listen_address(host)
    addresses = [str(listen)] if listen is not None else machine_addresses()
    properties = {"path": path, "api": "/api", "version": __version__}
    server = f"{hostname}.local."
    return [
        AsyncServiceInfo(
            kind,
            f"plotbridge on {hostname}.{kind}",
            port=port,
            parsed_addresses=addresses,
            server=server,
            properties=properties,
        )
        for kind in SERVICE_TYPES
    ]


def _zeroconf_for(host: str) -> AsyncZeroconf:
    listen = _listen_address(host)
    if listen is None:
        return AsyncZeroconf(interfaces=InterfaceChoice.All)
    version = IPVersion.V4Only if listen.version == 4 else IPVersion.V6Only
    return AsyncZeroconf(interfaces=[str(listen)], ip_version=version)


async def register(zc: AsyncZeroconf, infos: list[AsyncServiceInfo]) -> None:
    for info in infos:
        await zc.async_register_service(info, allow_name_change=True)
        log.info("announced %s on port %d", info.name, info.port)


@contextlib.asynccontextmanager
async def announced(host: str, port: int, enabled: bool = True) -> AsyncIterator[None]:
    """Announce the server while the block runs; never delays or breaks the server.

    Registration (its probes take about a second) runs beside the server; a
    machine without a usable network logs a warning and serves on.
    """
    if not enabled:
        yield
        return
    zc: AsyncZeroconf | None = None
    task: asyncio.Task[None] | None = None
    try:
        zc = _zeroconf_for(host)
        task = asyncio.create_task(register(zc, service_infos(host, port)), name="mdns")
        task.add_done_callback(_report)
    except OSError as exc:
        log.warning("zeroconf announcement unavailable: %s", exc)
    try:
        yield
    finally:
        if task is not None:
            task.cancel()
        if zc is not None:
            with contextlib.suppress(Exception):
                await asyncio.wait_for(zc.async_close(), UNREGISTER_WAIT_S)


def _report(task: asyncio.Task[None]) -> None:
    if not task.cancelled() and task.exception() is not None:
        log.warning("zeroconf announcement failed: %s", task.exception())


@dataclass
class Found:
    name: str
    url: str
    host: str
    port: int
    properties: dict[str, str]


def _decode(properties: dict[bytes, bytes | None]) -> dict[str, str]:
    return {k.decode(): (v or b"").decode() for k, v in properties.items()}


def _found(info: ServiceInfo) -> Found | None:
    addresses = info.parsed_scoped_addresses()
    if not addresses or info.port is None:
        return None
    address = addresses[0]
    host = f"[{address}]" if ":" in address else address
    properties = _decode(info.properties)
    return Found(
        name=info.name.removesuffix("." + PLOTBRIDGE_TYPE), host=address, port=info.port,
        url=f"http://{host}:{info.port}", properties=properties,
    )  # fmt: skip


SETTLE_S = 0.5  # s to keep listening after the first server answers


def discover(timeout: float = 3.0, interfaces: Any = None) -> list[Found]:
    """plotbridge servers answering on the LAN within `timeout` seconds (blocking)."""
    if interfaces is None:
        chosen = os.environ.get(INTERFACE_ENV)
        interfaces = chosen.split(",") if chosen else InterfaceChoice.All
    zc = Zeroconf(interfaces=interfaces)
    names: list[str] = []
    try:
        browser = ServiceBrowser(
            zc, PLOTBRIDGE_TYPE,
            handlers=[lambda zeroconf, service_type, name, state_change: names.append(name)],
        )  # fmt: skip
        deadline = time.monotonic() + timeout
        while not names and time.monotonic() < deadline:
            time.sleep(0.05)
        settled = min(deadline, time.monotonic() + SETTLE_S)
        while time.monotonic() < settled:  # the others announcing too (an impostor first)
            time.sleep(0.05)
        browser.cancel()
        found = []
        for name in dict.fromkeys(names):
            info = ServiceInfo(PLOTBRIDGE_TYPE, name)
            if info.request(zc, max(250, int((deadline - time.monotonic()) * 1000))):
                entry = _found(info)
                if entry is not None:
                    found.append(entry)
        return found
    finally:
        zc.close()
