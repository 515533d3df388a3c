"""The Python client sends a GET once more when its connection was dropped (a keep-alive
connection the server closed as the request went out), and never repeats anything else."""

from __future__ import annotations

import httpx
import pytest
from plotbridge.client import Plotbridge, PlotbridgeError


def client(failures: int, error: type[Exception] = httpx.ReadError) -> tuple[Plotbridge, list]:
    calls: list[str] = []

    def handle(request: httpx.Request) -> httpx.Response:
        calls.append(request.method)
        if len(calls) <= failures:
            raise error("Connection reset by peer", request=request)
        return httpx.Response(200, json={"status": "ok"})

    pb = Plotbridge("http://plotter.test", "t" * 16)
    pb._http = httpx.Client(base_url=pb.url, transport=httpx.MockTransport(handle))
    return pb, calls


@pytest.mark.parametrize("error", [httpx.ReadError, httpx.RemoteProtocolError,
                                   httpx.WriteError])
def test_a_get_on_a_dropped_connection_is_sent_once_more(error):
    pb, calls = client(1, error)
    assert pb.health()
    assert calls == ["GET", "GET"]


def test_a_get_dropped_twice_is_an_error_that_names_the_server():
    pb, calls = client(2)
    with pytest.raises(PlotbridgeError, match=r"cannot reach http://plotter\.test"):
        pb.health()
    assert calls == ["GET", "GET"]


def test_a_post_is_never_sent_twice():
    pb, calls = client(1)
    with pytest.raises(PlotbridgeError, match="cannot reach"):
        pb.request("POST", "/api/jobs/x/start", "start")
    assert calls == ["POST"]


def test_a_timeout_is_not_repeated():
    pb, calls = client(1, httpx.ReadTimeout)
    with pytest.raises(PlotbridgeError, match="cannot reach"):
        pb.health()
    assert calls == ["GET"]
