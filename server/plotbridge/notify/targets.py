"""Where a webhook from the settings may post: not to this machine (loopback, its own
addresses) nor to link-local addresses, unless `serve --webhook-allow-local` says so, so
the settings cannot be used to reach services that only listen locally (nor to map
which local ports answer). Checked when saved and again before each post (the name may
resolve elsewhere by then). `--webhook` URLs are the machine owner's and not checked."""

from __future__ import annotations

import asyncio
import ipaddress
from urllib.parse import urlsplit

from plotbridge.guard.hosts import own_names

RESOLVE_TIMEOUT_S = 3.0


class LocalTarget(ValueError):
    """A webhook URL that points at this machine or a link-local address."""


async def _addresses(host: str) -> set[str]:
    try:
        return {str(ipaddress.ip_address(host))}
    except ValueError:
        pass
    loop = asyncio.get_running_loop()
    try:  # asyncio.timeout, not wait_for: 3.11's wait_for may swallow a cancel that comes
        # as the lookup ends, and the delivery being closed then never ends (seen in a test)
        async with asyncio.timeout(RESOLVE_TIMEOUT_S):
            found = await loop.getaddrinfo(host, None)
    except (OSError, TimeoutError):
        return set()  # not resolvable now: checked again before each post
    return {str(info[4][0]).split("%")[0] for info in found}


async def own_addresses() -> set[str]:
    found: set[str] = set()
    for name in own_names():
        found |= await _addresses(name)
    return found


async def refuse_local(url: str) -> None:
    """LocalTarget saying why when `url` reaches this machine or a link-local address."""
    host = (urlsplit(url).hostname or "").rstrip(".").lower()
    addresses = await _addresses(host)
    own = await own_addresses()
    for text in addresses:
        address = ipaddress.ip_address(text)
        mapped = getattr(address, "ipv4_mapped", None)
        address = mapped or address
        why = ("a loopback address" if address.is_loopback
               else "a link-local address" if address.is_link_local
               else "an unspecified address" if address.is_unspecified
               else "this server's own address" if text in own or str(address) in own
               else None)  # fmt: skip
        if why:
            raise LocalTarget(f"webhook URL {url[:80]!r}: {host} is {why} ({address}); "
                              "start the server with --webhook-allow-local to allow it")


__all__ = ["LocalTarget", "refuse_local"]
