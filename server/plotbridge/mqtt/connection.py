"""The supervised broker connection: connects, reconnects with backoff, and keeps what
waits to be sent bounded, so a broker that is down, slow or hostile costs the LAN side
nothing.

- Outgoing state (retained) is coalesced per topic: the latest payload wins, so a slow
  broker sees fewer updates, never a growing queue. Events (not retained) wait in a short
  ring; the oldest are dropped when it is full. Publishing never waits.
- Incoming messages that must act at once (a STOP) are taken in the socket's read callback
  (`urgent`), ahead of anything queued; the rest wait in a bounded inbox (dropped when full).
- A problem (broker down, credentials refused, inbox full) is logged once, when it starts,
  and once when it is over, never per message or per retry.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import random
import ssl
from collections import deque
from collections.abc import Awaitable, Callable

import aiomqtt
from aiomqtt import Message

from plotbridge.mqtt.settings import MqttSettings

log = logging.getLogger("plotbridge.mqtt")
PAHO_LOG = logging.getLogger("plotbridge.mqtt.paho")  # paho's own lines: one per packet
PAHO_LOG.setLevel(logging.INFO)

EVENTS_KEPT = 64  # events waiting while the broker is slow or away
INBOX = 1000  # incoming messages waiting to be handled
PUBLISH_TIMEOUT = 10.0  # s a publish may wait for the broker before the link counts as broken
BACKOFF = (0.5, 15.0)  # s, first and longest wait between connection attempts
PROTOCOL_REFUSED = (1, 132)  # CONNACK: unacceptable protocol version (3.1.1, 5)


class Once:
    """Logs a problem when it starts and when it ends; repeats in between are counted."""

    def __init__(self) -> None:
        self._open: dict[str, int] = {}

    def warn(self, key: str, message: str, *args: object) -> None:
        if key in self._open:
            self._open[key] += 1
            return
        self._open[key] = 1
        log.warning(message, *args)

    def clear(self, key: str, message: str | None = None) -> None:
        count = self._open.pop(key, 0)
        if count and message:
            log.info("%s (it happened %d times)", message, count)


class Inbox(asyncio.Queue[Message]):
    """aiomqtt's incoming queue: urgent messages are handled as they arrive, the rest
    queued up to INBOX (beyond, dropped and counted)."""

    def __init__(self, urgent: Callable[[Message], bool], problems: Once, maxsize: int = 0):
        super().__init__(maxsize=INBOX)
        self._urgent = urgent
        self._problems = problems

    def put_nowait(self, item: Message) -> None:
        if self._urgent(item):
            return
        if self.full():
            self._problems.warn("inbox", "MQTT: messages arrive faster than they can be "
                                "handled; dropping the excess (a flood on the broker?)")
            return
        super().put_nowait(item)


class Connection:
    def __init__(self, settings: MqttSettings, *, client_id: str, will_topic: str,
                 on_connected: Callable[[], Awaitable[None]],
                 on_message: Callable[[Message], None],
                 urgent: Callable[[Message], bool], subscriptions: list[str]) -> None:  # fmt: skip
        self.settings = settings
        self.client_id = client_id
        self.will_topic = will_topic
        self.on_connected = on_connected
        self.on_message = on_message
        self.urgent = urgent
        self.subscriptions = subscriptions
        self.problems = Once()
        self.connected = False
        self.protocol = aiomqtt.ProtocolVersion.V5
        self._client: aiomqtt.Client | None = None
        self._state: dict[str, bytes] = {}  # retained, latest per topic
        self._events: deque[tuple[str, bytes]] = deque(maxlen=EVENTS_KEPT)
        self._wake = asyncio.Event()
        self._task: asyncio.Task[None] | None = None

    @property
    def where(self) -> str:
        s = self.settings
        return f"{'mqtts' if s.tls else 'mqtt'}://{s.host}:{s.port}"

    # ---- sending ------------------------------------------------------------------------

    def publish(self, topic: str, payload: bytes | str) -> None:
        """Retained state: sent when the broker takes it; a newer payload replaces it."""
        self._state[topic] = payload.encode() if isinstance(payload, str) else payload
        self._wake.set()

    def event(self, topic: str, payload: bytes | str) -> None:
        """A message that is not retained; the oldest waiting ones go when too many wait."""
        if len(self._events) == EVENTS_KEPT:
            self.problems.warn("events", "MQTT: the broker is slow or away; dropping events")
        self._events.append((topic, payload.encode() if isinstance(payload, str) else payload))
        self._wake.set()

    async def send_now(self, topic: str, payload: bytes | str, retain: bool = False) -> bool:
        """Sent at once, ahead of anything waiting (a STOP to another bridge): True when
        the broker acknowledged it."""
        client = self._client
        if client is None or not self.connected:
            return False
        try:
            await client.publish(topic, payload, qos=1, retain=retain, timeout=PUBLISH_TIMEOUT)
        except aiomqtt.MqttError as exc:
            log.warning("MQTT: could not send to %s: %s", topic, exc)
            return False
        return True

    # ---- the supervised loop ----------------------------------------------------------

    def start(self) -> None:
        self._task = asyncio.create_task(self._run(), name="mqtt")

    async def close(self) -> None:
        """Says `offline` (retained) and disconnects; the will is for deaths, not stops."""
        client = self._client
        if client is not None and self.connected:
            with contextlib.suppress(aiomqtt.MqttError, asyncio.TimeoutError):
                await asyncio.wait_for(client.publish(self.will_topic, "offline", qos=1,
                                                      retain=True), 2)  # fmt: skip
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(BaseException):
                await self._task

    async def _run(self) -> None:
        delay = BACKOFF[0]
        while True:
            try:
                await self._session()
            except aiomqtt.MqttCodeError as exc:
                code = getattr(exc.rc, "value", exc.rc)
                if self.protocol == aiomqtt.ProtocolVersion.V5 and code in PROTOCOL_REFUSED:
                    log.info("MQTT: %s does not speak MQTT 5; using 3.1.1", self.where)
                    self.protocol = aiomqtt.ProtocolVersion.V311
                    continue
                self._down(f"MQTT: {self.where} refused us: {exc}")
            except (aiomqtt.MqttError, OSError, ssl.SSLError) as exc:
                self._down(f"MQTT: no connection to {self.where}: {exc or type(exc).__name__}")
            except Exception:  # a bug: the connection must outlive it
                log.exception("MQTT: the session with %s failed", self.where)
            else:
                delay = BACKOFF[0]
            if self.connected:  # it had connected: start over quickly
                delay = BACKOFF[0]
            self.connected = False
            self._client = None
            await asyncio.sleep(delay * random.uniform(0.8, 1.2))
            delay = min(delay * 2, BACKOFF[1])

    def _down(self, message: str) -> None:
        self.problems.warn("connection", "%s; retrying with backoff (up to %g s) without "
                           "logging each try", message, BACKOFF[1])  # fmt: skip

    def _client_for_session(self) -> aiomqtt.Client:
        s = self.settings
        tls = None
        if s.tls:
            tls = ssl.create_default_context(cafile=str(s.ca_file) if s.ca_file else None)
        return aiomqtt.Client(
            s.host, s.port, username=s.username, password=s.password,
            identifier=self.client_id, protocol=self.protocol, keepalive=s.keepalive,
            will=aiomqtt.Will(self.will_topic, "offline", qos=1, retain=True),
            queue_type=functools.partial(Inbox, self.urgent, self.problems),  # type: ignore[arg-type]
            timeout=PUBLISH_TIMEOUT, tls_context=tls, logger=PAHO_LOG,
        )  # fmt: skip

    async def _session(self) -> None:
        client = self._client_for_session()
        async with client:
            self._client = client
            self.connected = True
            self.problems.clear("connection", f"MQTT: connected to {self.where} again")
            log.info("MQTT: connected to %s (MQTT %s) as %s", self.where,
                     "5" if self.protocol == aiomqtt.ProtocolVersion.V5 else "3.1.1",
                     self.client_id)  # fmt: skip
            for topic in self.subscriptions:
                await client.subscribe(topic, qos=1)
            await client.publish(self.will_topic, "online", qos=1, retain=True)
            await self.on_connected()
            tasks = {asyncio.create_task(self._read(client)),
                     asyncio.create_task(self._write(client))}
            try:
                done, _ = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
            finally:
                for task in tasks:
                    task.cancel()
                await asyncio.gather(*tasks, return_exceptions=True)
            for task in done:
                task.result()  # the reason the session ended

    async def _read(self, client: aiomqtt.Client) -> None:
        async for message in client.messages:
            try:
                self.on_message(message)
            except Exception:
                log.exception("MQTT: handling a message on %s failed", message.topic)

    async def _write(self, client: aiomqtt.Client) -> None:
        while True:
            await self._wake.wait()
            self._wake.clear()
            while self._events or self._state:
                if self._events:
                    topic, payload = self._events.popleft()
                    retain = False
                else:
                    topic = next(iter(self._state))
                    payload, retain = self._state.pop(topic), True
                try:
                    await client.publish(topic, payload, qos=1, retain=retain,
                                         timeout=PUBLISH_TIMEOUT)  # fmt: skip
                except aiomqtt.MqttError:
                    if retain:
                        self._state.setdefault(topic, payload)  # sent again on the next link
                    raise
            self.problems.clear("events")
