"""Roles in the page, in Chromium against a real server: a person logs in by a one-time
link; a viewer's page hides what a viewer cannot do; an operator approves a submitter's
upload from the approval list; an admin adds a person and sees the audit log."""

from __future__ import annotations

import httpx

from tests.browser.conftest import login, screenshot
from tests.fixtures.people import cli_key, plotbridge_cli
from tests.fixtures.waits import wait_until


def link_of(output: str) -> str:
    return next(word for word in output.split() if "/login.html#" in word)


def open_link(page, server, name: str, role: str) -> None:
    made = plotbridge_cli("users", "add", name, "--role", role, "--data-dir",
                          str(server.data_dir), "--host", "127.0.0.1", "--port", str(server.port))
    link = link_of(made.stdout)
    page.goto(link)
    page.click("#link-login")
    page.wait_for_selector("#app:not([hidden])")
    page.wait_for_selector("#who-am-i")


def test_a_viewer_logs_in_by_link_and_sees_only_what_a_viewer_may_do(desktop, server_virtual):
    page, _ = desktop
    open_link(page, server_virtual, "vera", "viewer")
    assert page.text_content("#who-am-i") == "vera (viewer)"
    for hidden in ('section[aria-labelledby="add-title"]', '.tab[data-tab="control"]',
                   '.tab[data-tab="console"]', '.tab[data-tab="settings"]', "#hold"):  # fmt: skip
        assert not page.is_visible(hidden), hidden
    assert page.is_visible("#estop")  # STOP for everyone
    assert page.is_visible("#logout-everywhere")
    screenshot(page, "roles-viewer")
    page.goto(page.url.split("#")[0])  # the link is used up: a second use fails
    again = httpx.post(f"{server_virtual.url}/api/login", json={"link": "x" * 32})
    assert again.status_code == 401


def test_an_operator_approves_a_submitters_upload_from_the_list(desktop, server_virtual):
    page, _ = desktop
    key = cli_key(server_virtual.data_dir, "student", "submitter")
    sent = httpx.post(f"{server_virtual.url}/api/jobs", headers={"Authorization": f"Bearer {key}"},
                      files={"file": ("kite.gcode", "G21\nG1 X10 Y10 F1000\n")},
                      timeout=60).json()  # fmt: skip
    assert sent["state"] == "awaiting_approval"
    open_link(page, server_virtual, "olga", "operator")
    row = f'#approval-list li[data-job="{sent["id"]}"]'
    page.wait_for_selector(row)
    assert "from key student" in page.text_content(row)
    screenshot(page, "roles-approvals")
    page.click(f"{row} button.primary")
    wait_until(lambda: server_virtual.job(sent["id"]), lambda j: j["state"] == "queued", 10,
               "the approved job queued")  # fmt: skip
    page.wait_for_selector(row, state="detached")


def test_an_admin_adds_a_person_and_reads_the_audit_log(desktop, server_virtual):
    page, _ = desktop
    login(page, server_virtual.url, server_virtual.token)
    page.click('.tab[data-tab="settings"]')
    page.wait_for_selector("#people-add")
    page.fill("#people-name", "tom")
    page.select_option("#people-role", "submitter")
    page.click('#people-add button[type="submit"]')
    page.wait_for_function("() => document.querySelector('#people-shown').textContent"
                           ".includes('/login.html#')")  # fmt: skip
    page.wait_for_selector('#people-list li[data-name="tom"]')
    page.wait_for_function("() => document.querySelector('#audit-list').textContent"
                           ".includes('POST /api/people')")  # fmt: skip
    screenshot(page, "roles-admin")
