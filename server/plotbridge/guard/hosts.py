"""Host allow-list against DNS rebinding.

A page on a rebound name (evil.example resolving to this machine) sends that
name as Host. So only our own names pass: localhost, the host name, its
zeroconf (`.local`) name and fully qualified name, and names given with
--allowed-host. Any IP literal passes: rebinding needs a name the attacker
controls, and a literal address cannot be one.
"""

from __future__ import annotations

import ipaddress
import socket
from collections.abc import Iterable


def own_names(extra: Iterable[str] = ()) -> frozenset[str]:
    name = socket.gethostname().lower()
    names = {"localhost", name, f"{name}.local", socket.getfqdn().lower()}
    names.update(n.strip().lower().rstrip(".") for n in extra if n.strip())
    return frozenset(names)


def host_name(host_header: str) -> str:
    """The name part of a Host header ('[::1]:8000' -> '::1', 'pi:8000' -> 'pi')."""
    host = host_header.strip().lower()
    if host.startswith("["):
        return host[1:].partition("]")[0]
    if host.count(":") == 1:
        host = host.partition(":")[0]
    return host.rstrip(".")


def host_allowed(host_header: str | None, names: frozenset[str]) -> bool:
    if not host_header:
        return False
    name = host_name(host_header)
    if name in names:
        return True
    try:
        ipaddress.ip_address(name)
    except ValueError:
        return False
    return True


def origin_allowed(origin: str | None, host: str | None) -> bool:
    """Absent (a script, not a browser) or the same host:port as the request."""
    if origin is None:
        return True
    if not host:
        return False
    _, sep, rest = origin.partition("://")
    return bool(sep) and rest.rstrip("/").lower() == host.lower()
