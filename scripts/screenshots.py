"""Screenshots of every page of the web UI at 1400x900 and 390x844, for review and for the
README (`make screenshots`).

Starts a real server with three virtual plotters (or uses --url/--token), fills it with
what a plotter user has after a while (pens, a three-layer job with pens per layer, a job
plotting, a stopped one, finished ones), then renders each tab in Debian's Chromium into
OUT (default: screenshots/). Prints each file written, and any console error (exit 1).
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
from playwright.sync_api import sync_playwright

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.fixtures.drawings import THREE_LAYERS, drawing  # noqa: E402
from tests.fixtures.server import running_server  # noqa: E402

SIZES = {"desktop": {"width": 1400, "height": 900}, "phone": {"width": 390, "height": 844}}
TABS = ["plot", "history", "control", "pens", "settings", "console"]
CHROMIUM = "/usr/bin/chromium"


def wait(check, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while not check():
        if time.monotonic() > deadline:
            raise TimeoutError("the demo server did not get there in time")
        time.sleep(0.3)


def stage(client: httpx.Client) -> None:
    """A plotter user's afternoon: pens, finished jobs, one stopped, one plotting."""
    names = [p["name"] for p in client.get("/api/plotters").json()]
    for name in names:
        wait(lambda n=name: client.get(f"/api/plotters/{n}/machine").json()["connected"])
        client.post(f"/api/plotters/{name}/machine/home", timeout=180).raise_for_status()
    pens = {}
    for pen in ({"name": "Black fineliner", "colour": "#111111"},
                {"name": "Red brush pen", "colour": "#d40000"},
                {"name": "Blue gel", "colour": "#1c5fd4"}):  # fmt: skip
        made = client.post("/api/pens", json={**pen, "up_us": 1000, "down_us": 2000})
        pens[pen["name"]] = made.json()["id"]

    def upload(name: str, body: str | bytes, **data: str) -> dict:
        answer = client.post("/api/jobs", files={"file": (name, body)}, data={"name": name, **data})
        answer.raise_for_status()
        return answer.json()

    quick = upload("coaster.gcode", drawing(circles=1), plotter=names[0])
    client.post(f"/api/jobs/{quick['id']}/start").raise_for_status()
    wait(lambda: client.get(f"/api/jobs/{quick['id']}").json()["state"] == "done")
    cancelled = upload("test-card.gcode", drawing(circles=2))
    client.post(f"/api/jobs/{cancelled['id']}/cancel").raise_for_status()
    layered = upload("poster.svg", THREE_LAYERS)
    per_layer = {"1": pens["Black fineliner"], "2": pens["Red brush pen"], "3": pens["Blue gel"]}
    client.patch(f"/api/jobs/{layered['id']}", json={"pens": per_layer}).raise_for_status()
    if len(names) > 1:
        stopped = upload("spiral.gcode", drawing(circles=12), plotter=names[1], start="true")
        wait(lambda: client.get(f"/api/jobs/{stopped['id']}").json()["lines_done"] > 40)
        client.post(f"/api/plotters/{names[1]}/machine/estop").raise_for_status()
        wait(lambda: client.get(f"/api/jobs/{stopped['id']}").json()["state"] == "stopped")
    running = upload("circles.gcode", drawing(circles=15), plotter=names[0], start="true")
    wait(lambda: client.get(f"/api/jobs/{running['id']}").json()["lines_done"] > 20)
    upload("next-in-line.gcode", drawing(circles=3))


@contextlib.contextmanager
def demo_server(tmp: Path) -> Iterator[tuple[str, str]]:
    with running_server(tmp / "data", ["--virtual", "3", "--sim-speed", "1"]) as server:
        stage(server.client)
        yield server.url, server.token


def shoot(url: str, token: str, out: Path) -> list[str]:
    out.mkdir(parents=True, exist_ok=True)
    errors: list[str] = []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM,
                                     args=["--no-sandbox", "--disable-gpu"])  # fmt: skip
        for size, viewport in SIZES.items():
            phone = size == "phone"
            context = browser.new_context(viewport=viewport, is_mobile=phone, has_touch=phone,
                                          device_scale_factor=2 if phone else 1)  # fmt: skip
            page = context.new_page()
            page.on("console", lambda m, at=size: errors.append(f"{at}: {m.text}")
                    if m.type == "error" else None)  # fmt: skip
            page.on("pageerror", lambda exc, at=size: errors.append(f"{at}: {exc}"))
            page.goto(f"{url}/")
            page.wait_for_selector("#login-view:not([hidden])")
            page.screenshot(path=str(out / f"login-{size}.png"))
            page.fill("#login-token", token)  # logged in as a person would, by the form
            page.click("#login-submit")
            page.wait_for_selector("#app:not([hidden])")
            page.wait_for_function("() => window.plotbridge.store.state.socket.status === 'open'")
            for tab in TABS:
                page.click(f'.tab[data-tab="{tab}"]')
                page.wait_for_selector(f"#tab-{tab}:not([hidden])")
                page.wait_for_timeout(800)  # the preview's progressive render, the settings read
                path = out / f"{tab}-{size}.png"
                page.screenshot(path=str(path), full_page=phone)
                print(path)
            context.close()
        browser.close()
    return errors


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "screenshots")
    parser.add_argument("--url", help="an existing server (else a demo server is started)")
    parser.add_argument("--token", help="its token")
    parser.add_argument("--readme", action="store_true", help="also copy plot-desktop.png to docs/")
    args = parser.parse_args()
    if args.url:
        errors = shoot(args.url.rstrip("/"), args.token or "", args.out)
    else:
        with tempfile.TemporaryDirectory() as tmp, demo_server(Path(tmp)) as (url, token):
            errors = shoot(url, token, args.out)
    if args.readme:
        (REPO / "docs" / "screenshot.png").write_bytes((args.out / "plot-desktop.png").read_bytes())
    for error in errors:
        print("console error:", error, file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
