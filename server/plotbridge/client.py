"""The Python client of a plotbridge server.

    from plotbridge.client import Plotbridge

    with Plotbridge("http://plotter.local:8000", token="...") as pb:
        job = pb.upload("art.svg", paper="a4", fit=True)
        pb.start(job["id"])
        pb.wait(job["id"], progress=lambda job: print(job["progress"]))

The URL and token default to `PLOTBRIDGE_URL` and `PLOTBRIDGE_TOKEN` (or a
token file: `token_file=` or `PLOTBRIDGE_TOKEN_FILE`); the token may be an API key
(`plotbridge keys add`). Without a URL the client looks for servers on the LAN
(zeroconf) and sends its key only to one that proves it holds that key; with
`server_id=` (or `PLOTBRIDGE_SERVER_ID`: the id `keys add` printed) a server at a given
URL must prove that too, and be that server. Every failure is a `PlotbridgeError`
whose message says what the server answered.
"""

from __future__ import annotations

import hmac
import json
import os
import secrets
import time
from collections.abc import AsyncIterator, Callable, Iterable
from pathlib import Path
from typing import IO, Any
from urllib.parse import quote, urlencode

import httpx

from plotbridge.people.proof import digest, key_id, server_proof

Job = dict[str, Any]
PLACEMENT = ("paper", "margin", "fit", "rotate", "scale", "dx", "dy", "optimize", "pen_dialect")
DISCOVER_TIMEOUT_S = 3.0
NO_ROUTE = (404, 405)  # a server from before several plotters (its web UI answers the path)


GOING_ON = ("stop", "start")  # a job with one of these actions runs, or is yet to run


def going_on(job: Job) -> bool:
    """Whether the job runs or will (its actions say so, or it waits for a plotter)."""
    return bool(job.get("waiting")) or any(a in job.get("actions", ()) for a in GOING_ON)


def _follow(read: Callable[[], tuple[Job, bool]], progress: Callable[[Job], None] | None,
            timeout: float | None, poll: float, what: str) -> Job:
    """Polls `read()` (the thing followed, whether it is over) every `poll` s until it is
    over; TimeoutError naming `what` past `timeout`."""
    deadline = None if timeout is None else time.monotonic() + timeout
    while True:
        item, over = read()
        if progress is not None:
            progress(item)
        if over:
            return item
        if deadline is not None and time.monotonic() > deadline:
            raise TimeoutError(f"{what} still {item.get('state')} after {timeout:g} s")
        time.sleep(poll)


class PlotbridgeError(Exception):
    """A request that failed: `status` (None when the server was not reached) and `detail`."""

    def __init__(self, message: str, status: int | None = None, detail: Any = None) -> None:
        super().__init__(message)
        self.status = status
        self.detail = detail


class SetupError(PlotbridgeError):
    """The client cannot start: no token, an unreadable token file, no server found."""


def describe_detail(detail: Any) -> str:
    """The server's `detail` as lines a person reads (upload errors with their line; a
    refused action with what the job allows now)."""
    if isinstance(detail, dict) and "actions" in detail and "message" in detail:
        allowed = ", ".join(detail["actions"]) or "nothing, for now"
        return f"{detail['message']} (it allows: {allowed})"
    if isinstance(detail, dict) and "message" in detail:
        return str(detail["message"])
    if isinstance(detail, dict) and isinstance(detail.get("errors"), list):
        return "\n".join(
            f"  line {e.get('line')}: {e.get('message')}" if e.get("line") else
            f"  {e.get('message')}"
            for e in detail["errors"]
        )  # fmt: skip
    if isinstance(detail, list):  # validation errors: [{"loc", "msg"}]
        return "\n".join(
            f"  {'.'.join(str(p) for p in e.get('loc', []))}: {e.get('msg')}"
            if isinstance(e, dict) else f"  {e}"
            for e in detail
        )  # fmt: skip
    return str(detail)


def read_token(token: str | None = None, token_file: str | os.PathLike[str] | None = None) -> str:
    """The token: given, else `PLOTBRIDGE_TOKEN`, else the token file (given or from the env)."""
    token = token or os.environ.get("PLOTBRIDGE_TOKEN")
    if token:
        return token.strip()
    path = token_file or os.environ.get("PLOTBRIDGE_TOKEN_FILE")
    if not path:
        raise SetupError("no token: pass one, or set PLOTBRIDGE_TOKEN or PLOTBRIDGE_TOKEN_FILE")
    try:
        text = Path(path).expanduser().read_text().strip()
    except OSError as exc:
        raise SetupError(f"cannot read the token file {path}: {exc.strerror}") from exc
    if not text:
        raise SetupError(f"the token file {path} is empty")
    return text


def proves(url: str, token: str, server_id: str | None = None) -> bool:
    """Does the server at `url` hold this key (and is it `server_id`, when given)? Asked
    without sending the key: the server answers an HMAC only the key's maker can."""
    nonce = secrets.token_hex(16)
    try:
        answer = httpx.get(f"{url}/api/identity", params={"key": key_id(token), "nonce": nonce},
                           timeout=5.0).json()  # fmt: skip
        proof, server = str(answer.get("proof")), str(answer.get("server"))
    except (httpx.HTTPError, ValueError, AttributeError):
        return False
    expected = server_proof(digest(token), nonce, server)
    return hmac.compare_digest(proof, expected) and server_id in (None, server)


def find_url(token: str, server_id: str | None = None, timeout: float = DISCOVER_TIMEOUT_S) -> str:
    """The URL of the one server on the LAN that proves it holds this key (zeroconf only
    proposes: an impostor announcing itself never gets the key)."""
    from plotbridge.mdns import discover

    try:
        found = discover(timeout)
    except OSError as exc:
        raise SetupError(f"no server URL and no LAN search possible: {exc}") from exc
    if not found:
        raise SetupError(
            f"no plotbridge server answered on the LAN within {timeout:g} s: "
            "pass --url or set PLOTBRIDGE_URL"
        )
    urls = list(dict.fromkeys(f.url for f in found))
    holding = [url for url in urls if proves(url, token, server_id)]
    if not holding:
        raise SetupError(f"{len(urls)} server(s) announced on the LAN ({', '.join(urls)}), none "
                         "holds this key: pass --url, or a key made for one of them")
    if len(holding) > 1:
        raise SetupError(f"several servers hold this key, choose one with --url: "
                         f"{', '.join(holding)}")  # fmt: skip
    return holding[0]


class Plotbridge:
    """One server. A context manager; also usable plainly (then call `close()`)."""

    def __init__(
        self,
        url: str | None = None,
        token: str | None = None,
        *,
        token_file: str | os.PathLike[str] | None = None,
        timeout: float = 60.0,
        server_id: str | None = None,
    ) -> None:
        self.token = read_token(token, token_file)
        server_id = server_id or os.environ.get("PLOTBRIDGE_SERVER_ID") or None
        url = url or os.environ.get("PLOTBRIDGE_URL") or os.environ.get("PLOTBRIDGE_SERVER")
        self.url = (url or find_url(self.token, server_id)).rstrip("/")
        if "://" not in self.url:
            self.url = f"http://{self.url}"
        if url and server_id and not proves(self.url, self.token, server_id):
            raise SetupError(f"{self.url} is not server {server_id}, or does not hold this key: "
                             "the key is not sent")  # fmt: skip
        self._http = httpx.Client(
            base_url=self.url, timeout=timeout,
            headers={"Authorization": f"Bearer {self.token}"},
        )  # fmt: skip

    def __enter__(self) -> Plotbridge:
        return self

    def __exit__(self, *_: object) -> None:
        self.close()

    def close(self) -> None:
        self._http.close()

    # ---- plumbing -------------------------------------------------------------------

    def request(self, method: str, path: str, what: str, **kwargs: Any) -> Any:
        """One call; the decoded JSON answer (None for an empty one) or PlotbridgeError.

        A GET that meets a dropped connection is sent once more, on a new one: the
        server closes a keep-alive connection after 5 s idle, and a request sent just
        then is reset (a script polling every few seconds meets it now and then)."""
        try:
            try:
                response = self._http.request(method, path, **kwargs)
            except (httpx.NetworkError, httpx.RemoteProtocolError):
                if method != "GET":
                    raise
                response = self._http.request(method, path, **kwargs)
        except httpx.HTTPError as exc:
            raise SetupError(f"cannot reach {self.url}: {exc}") from exc  # no server: exit 2
        if response.is_error:
            try:
                detail = response.json().get("detail")
            except (ValueError, AttributeError):
                detail = response.text.strip() or response.reason_phrase
            raise PlotbridgeError(
                f"{what} failed ({response.status_code}):\n{describe_detail(detail)}",
                response.status_code, detail,
            )  # fmt: skip
        return response.json() if response.content else None

    @staticmethod
    def _board(plotter: str | None) -> str:
        return f"/api/plotters/{quote(plotter, safe='')}" if plotter else "/api"

    # ---- server, plotters, machine -----------------------------------------------------

    def health(self) -> bool:
        return self.request("GET", "/api/health", "health check").get("status") == "ok"

    def server(self) -> dict[str, Any]:
        return self.request("GET", "/api/server", "server info")

    def plotters(self) -> list[dict[str, Any]]:
        """Every plotter (`name`, `machine`, ...); a single-plotter server lists its one."""
        try:
            return self.request("GET", "/api/plotters", "plotter list")
        except PlotbridgeError as exc:
            if exc.status not in NO_ROUTE:
                raise
        return [{"name": None, "machine": self.machine()}]

    def machine(self, plotter: str | None = None) -> dict[str, Any]:
        return self.request("GET", f"{self._board(plotter)}/machine", "machine state")

    def stop(self, plotter: str | None = None, *, all: bool = False) -> dict[str, Any]:
        """Emergency stop: one plotter (default the first) or, with `all`, every plotter."""
        if all:
            try:
                return self.request("POST", "/api/estop", "emergency stop", timeout=10)
            except PlotbridgeError as exc:
                if exc.status not in NO_ROUTE:  # a single-plotter server: its one machine
                    raise
        return self.request(
            "POST", f"{self._board(plotter)}/machine/estop", "emergency stop", timeout=10
        )

    def home(self, plotter: str | None = None) -> dict[str, Any]:
        """Run homing; `{"responses", "machine"}`, the machine as homing left it."""
        return self.request("POST", f"{self._board(plotter)}/machine/home", "homing", timeout=180)

    def unlock(self, plotter: str | None = None) -> dict[str, Any]:
        return self.request("POST", f"{self._board(plotter)}/machine/unlock", "unlock")

    def trace(self, plotter: str | None = None) -> dict[str, Any]:
        """What a virtual plotter's pen drew (404 from a real board)."""
        return self.request("GET", f"{self._board(plotter)}/sim/trace", "trace")

    # ---- jobs --------------------------------------------------------------------------

    def jobs(self) -> list[Job]:
        return self.request("GET", "/api/jobs", "job list")

    def job(self, job_id: str) -> Job:
        return self.request("GET", f"/api/jobs/{job_id}", "job")

    def upload(
        self,
        source: str | os.PathLike[str] | bytes | IO[bytes],
        *,
        filename: str | None = None,
        name: str | None = None,
        layers: Iterable[str] | None = None,
        plotter: str | None = None,
        start: bool = False,
        pens: dict[str, str | int | None] | None = None,
        fleet: bool = False,
        **placement: Any,
    ) -> Job:
        """Upload a file (a path), or a drawing in memory (bytes or a binary file object,
        with `filename` naming its format: "art.svg"). `layers` imports only those SVG
        layers (labels, ids or stroke colours); `pens` names the pen of some layers
        ({layer number or name: pen name or id}); `fleet` hands it to the MQTT fleet's
        queue (the first free fitting plotter of any bridge; its `fleet` says where it is).
        Placement keywords: paper, margin, fit, rotate, scale, dx, dy, optimize,
        pen_dialect. The new job."""
        unknown = set(placement) - set(PLACEMENT)
        if unknown:
            raise TypeError(f"unknown placement option(s): {', '.join(sorted(unknown))}")
        fields: dict[str, str] = {}
        for key, value in placement.items():
            if value is not None:
                fields[key] = str(value).lower() if isinstance(value, bool) else str(value)
        if layers is not None:
            fields["layers"] = ",".join(layers)
        if plotter:
            fields["plotter"] = plotter
        if pens:
            fields["pens"] = json.dumps(pens)
        if start:
            fields["start"] = "true"
        if fleet:
            fields["fleet"] = "true"
        if isinstance(source, (str, os.PathLike)):
            path = Path(source)
            if not path.is_file():
                raise PlotbridgeError(f"no such file: {path}")
            filename = filename or path.name
            fields["name"] = name or filename
            with path.open("rb") as fh:
                return self._post_upload(fields, filename, fh)
        filename = filename or "drawing"
        fields["name"] = name or filename
        return self._post_upload(fields, filename, source)

    def _post_upload(self, fields: dict[str, str], filename: str, body: Any) -> Job:
        files = {"file": (filename, body)}
        job = self.request("POST", "/api/jobs", "upload", data=fields, files=files)
        if job.get("start_error"):
            raise PlotbridgeError(f"uploaded as job {job['id']}, but it did not start: "
                                  f"{describe_detail(job['start_error'])}", 409, job)  # fmt: skip
        return job

    def start(self, job_id: str, plotter: str | None = None, *,
              layers: Iterable[int] | None = None,
              pens: dict[str, str | int | None] | None = None) -> Job:  # fmt: skip
        """Start a queued job (on `plotter`, where the server drives several); `layers`:
        plot only these (1-based numbers); `pens`: {layer: pen} as for `upload`."""
        params = {"plotter": plotter} if plotter else None
        body = {key: value for key, value in (("layers", list(layers or [])), ("pens", pens))
                if value}  # fmt: skip
        return self.request("POST", f"/api/jobs/{job_id}/start", "start", params=params,
                            json=body or None)  # fmt: skip

    # ---- pens ------------------------------------------------------------------------

    def pens(self) -> list[dict[str, Any]]:
        """The pen library: every pen with its settings and odometer."""
        return self.request("GET", "/api/pens", "list the pens")

    def add_pen(self, name: str, **settings: Any) -> dict[str, Any]:
        """A new pen: colour, up_us, down_us, speed, accel, reink_m (all optional)."""
        return self.request("POST", "/api/pens", "add a pen", json={"name": name, **settings})

    def set_pens(self, job_id: str, pens: dict[str, str | int | None]) -> Job:
        """Which pen draws which layer of a job that does not run."""
        return self.request("PATCH", f"/api/jobs/{job_id}", "set the pens",
                            json={"pens": pens})  # fmt: skip

    def active_jobs(self) -> list[Job]:
        """The jobs a plotter runs now (running, held, or waiting for a pen): those that
        can be stopped."""
        return [job for job in self.jobs() if "stop" in job.get("actions", ())]

    def fleet(self) -> dict[str, Any]:
        """The MQTT fleet as this server sees it: bridges, plotters, its fleet jobs."""
        return self.request("GET", "/api/fleet", "read the fleet")

    def active_job(self) -> Job | None:
        """The first job a plotter runs now, if any."""
        return next(iter(self.active_jobs()), None)

    def act(self, job_id: str, action: str, plotter: str | None = None,
            body: dict[str, Any] | None = None) -> Job:  # fmt: skip
        """One of the job's `actions` (start, hold, continue, stop, resume, home_then_resume,
        resume_from, restart, cancel, frame, approve, decline with {"reason"}); the server
        answers 409 with the actions it allows when the job's state does not."""
        params = {"plotter": plotter} if plotter else None
        return self.request("POST", f"/api/jobs/{job_id}/{action}", action.replace("_", " "),
                            params=params, json=body)  # fmt: skip

    def _job_or_active(self, job_id: str | None, action: str) -> str:
        if job_id:
            return job_id
        job = self.active_job()
        if job is None:
            raise PlotbridgeError(f"nothing to {action}: no job is running", 409)
        return job["id"]

    def pause(self, job_id: str | None = None) -> Job:
        """Hold a job (default: the running one)."""
        return self.act(self._job_or_active(job_id, "hold"), "hold")

    def resume(self, job_id: str | None = None) -> Job:
        """`continue` a held job or a pen change, or `resume` a stopped or interrupted one
        (default: the active one), whichever its `actions` offer."""
        job = self.job(self._job_or_active(job_id, "resume"))
        action = next((a for a in ("continue", "resume") if a in job.get("actions", ())), None)
        if action is None:
            raise PlotbridgeError(f"job {job['id']} is {job['state']}: nothing to resume "
                                  f"(it allows: {', '.join(job.get('actions', []))})", 409, job)
        return self.act(job["id"], action)

    def cancel(self, job_id: str) -> Job:
        return self.act(job_id, "cancel")

    def delete(self, job_id: str) -> None:
        self.request("DELETE", f"/api/jobs/{job_id}", "delete")

    def wait(
        self,
        job_id: str,
        progress: Callable[[Job], None] | None = None,
        *,
        timeout: float | None = None,
        poll: float = 0.5,
    ) -> Job:
        """Block until the job neither runs nor waits to (done, failed, cancelled, stopped,
        interrupted: nothing in its `actions` keeps it going); the last job. `progress(job)`
        is called on every poll. TimeoutError past `timeout`."""
        def read() -> tuple[Job, bool]:
            job = self.job(job_id)
            return job, not going_on(job)

        return _follow(read, progress, timeout, poll, f"job {job_id}")

    def wait_fleet(
        self,
        fleet_id: str,
        progress: Callable[[Job], None] | None = None,
        *,
        timeout: float | None = None,
        poll: float = 0.5,
    ) -> Job:
        """Block until a fleet job (`upload(fleet=True)`'s `fleet.id`) has settled on the
        bridge that took it; its record from `GET /api/fleet` (`job_state`, `bridge`,
        `plotter`, `progress`), its `state` the job's there (or where the fleet has it:
        offered, granted). `progress(record)` is called on every poll."""
        def read() -> tuple[Job, bool]:
            record = next((j for j in self.fleet().get("jobs", []) if j.get("id") == fleet_id),
                          None)  # fmt: skip
            if record is None:
                raise PlotbridgeError(f"fleet job {fleet_id} is not known to this bridge")
            state = record["job_state"] if record["state"] == "committed" else record["state"]
            return {**record, "state": state}, bool(record.get("settled"))

        return _follow(read, progress, timeout, poll, f"fleet job {fleet_id}")

    # ---- events ------------------------------------------------------------------------

    def events_url(self) -> str:
        scheme = "wss" if self.url.startswith("https") else "ws"
        return f"{scheme}{self.url[self.url.index(':'):]}/api/ws?{urlencode({'token': self.token})}"

    async def events(self) -> AsyncIterator[dict[str, Any]]:
        """The server's events (`machine`, `job`, `log`, ...) as they come, one dict each:

            async for event in pb.events():
                if event["type"] == "job": ...
        """
        from websockets.asyncio.client import connect
        from websockets.exceptions import InvalidStatus, WebSocketException

        try:
            async with connect(self.events_url(), max_size=2**22, open_timeout=30) as ws:
                async for text in ws:
                    yield json.loads(text)
        except InvalidStatus as exc:
            raise PlotbridgeError(f"events refused: {exc}", exc.response.status_code) from exc
        except (OSError, WebSocketException) as exc:
            raise PlotbridgeError(f"events from {self.url} ended: {exc}") from exc
