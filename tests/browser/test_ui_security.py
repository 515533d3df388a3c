"""The browser side of the hardening: another origin cannot act, the CSP holds,
a refused WebSocket leads to the login, a login link leaves no token behind."""

from __future__ import annotations

import functools
import http.server
import threading
import time
from collections.abc import Iterator

import pytest
from plotbridge.people.store import TOKEN_OWNER, PeopleStore

from tests.browser.conftest import QuietHandler, login
from tests.fixtures.people import plotbridge_cli
from tests.fixtures.waits import wait_until

pytestmark = pytest.mark.e2e

EVIL = """<!doctype html><html><body>
<form id="f" method="post" action="{url}/api/machine/estop" target="sink"></form>
<iframe name="sink"></iframe>
<script>
  const data = new FormData();
  data.append("file", new Blob(["G1 X1 Y1\\n"]), "evil.gcode");
  data.append("start", "true");
  fetch("{url}/api/jobs", {{method: "POST", mode: "no-cors", credentials: "include", body: data}})
    .finally(() => {{ document.getElementById("f").submit(); window.done = true; }});
</script></body></html>"""


@pytest.fixture
def evil_site(tmp_path, server_virtual) -> Iterator[str]:
    """A page on another port of the same host (same site, other origin)."""
    (tmp_path / "index.html").write_text(EVIL.format(url=server_virtual.url))
    handler = functools.partial(QuietHandler, directory=str(tmp_path))
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}/index.html"
    finally:
        httpd.shutdown()
        httpd.server_close()


def test_a_page_on_another_port_cannot_start_or_stop_anything(desktop, server_virtual, evil_site):
    page, _ = desktop
    login(page, server_virtual.url, server_virtual.token)
    other = page.context.new_page()
    other.goto(evil_site)
    other.wait_for_function("() => window.done === true")
    # both POSTs (the upload's, then the form's in the frame) have landed and were refused
    wait_until(server_virtual.log, lambda log: log.count("refused cross-site POST") >= 2, 10,
               "two refused cross-site POSTs in the server log")
    assert "refused cross-site POST /api/jobs " in server_virtual.log()
    assert "refused cross-site POST /api/machine/estop " in server_virtual.log()
    assert server_virtual.client.get("/api/jobs").json() == []
    assert "EMERGENCY STOP" not in server_virtual.log()
    # The page itself still can.
    page.click("#estop")
    wait_until(server_virtual.log, lambda log: "EMERGENCY STOP" in log, 10,
               "the page's own stop in the server log")


def test_the_csp_blocks_an_inline_script(desktop, server_virtual):
    page, _ = desktop
    violations: list[str] = []
    page.on("console", lambda msg: violations.append(msg.text))
    login(page, server_virtual.url, server_virtual.token)
    page.evaluate("""() => {
        window.injected = false;
        const s = document.createElement("script");
        s.textContent = "window.injected = true";
        document.head.appendChild(s);
    }""")
    assert page.evaluate("() => window.injected") is False
    assert any("Content Security Policy" in text for text in violations), violations


def test_a_refused_websocket_shows_the_login_and_stops_retrying(desktop, server_virtual):
    """Sessions ended behind the page's back (by another process, then a restart) end
    the page's session: its reconnect is refused with 4401, it shows the login and tries
    no more."""
    page, _ = desktop
    login(page, server_virtual.url, server_virtual.token)
    sockets: list[str] = []
    page.on("websocket", lambda ws: sockets.append(ws.url))
    store = PeopleStore(server_virtual.data_dir / "plotbridge.db")
    store.end_sessions(TOKEN_OWNER, "token")
    store.close()
    server_virtual.restart()
    page.wait_for_selector("#login-view:not([hidden])", timeout=60000)
    tried = len(sockets)
    time.sleep(3.0)  # retries would come every 0.5-10 s
    assert len(sockets) == tried


def test_a_login_link_leaves_no_secret_in_the_address_bar(desktop, server_virtual):
    """A one-time link's code leaves the address bar before anything is pressed; the token's
    old link (/login?token=) lands on / with a session."""
    page, _ = desktop
    made = plotbridge_cli("users", "add", "lee", "--role", "viewer", "--data-dir",
                          str(server_virtual.data_dir), "--host", "127.0.0.1",
                          "--port", str(server_virtual.port))  # fmt: skip
    link = next(word for word in made.stdout.split() if "/login.html#" in word)
    page.goto(link)
    page.wait_for_selector("#link-login:not([disabled])")
    assert "#" not in page.evaluate("() => location.href")
    page.context.clear_cookies()
    page.goto(f"{server_virtual.url}/login?token={server_virtual.token}")
    page.wait_for_selector("#app:not([hidden])")
    assert server_virtual.token not in page.evaluate("() => location.href")
