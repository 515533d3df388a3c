"""The console's confirmation of lines that wedge or wipe the board, in headless
Chromium against a real server and the virtual plotter."""

from __future__ import annotations

import pytest

from tests.browser.conftest import login

pytestmark = pytest.mark.browser


def test_sleep_and_reset_lines_are_sent_only_once_confirmed(desktop, server, plotter):
    page, errors = desktop
    server.wait_machine(lambda m: m["connected"], 30)
    login(page, server.url, server.token)
    page.click(".tab[data-tab=console]")
    asked: list[str] = []

    def answer(accept: bool):
        def handle(dialog) -> None:
            asked.append(dialog.message)
            dialog.accept() if accept else dialog.dismiss()
        return handle

    page.once("dialog", answer(False))
    page.fill("#command-line", "$SLP")
    page.press("#command-line", "Enter")
    page.wait_for_function(
        "() => document.querySelector('#command-error').textContent === '$SLP not sent'")
    assert "sleep" in asked[0] and "Send $SLP?" in asked[0]
    assert not [line for line in page.locator("#log li.tx").all_text_contents() if "SLP" in line]

    page.once("dialog", answer(True))
    page.fill("#command-line", "$RST=#")
    page.press("#command-line", "Enter")  # asked once the server's 428 is back
    page.wait_for_function("""() => [...document.querySelectorAll('#log li.tx')]
        .some((li) => li.textContent.includes('$RST=#'))""")
    assert "coordinate offsets" in asked[1]
    # sent, and the board clears its stored offsets (G54 on every board): no error shown
    page.wait_for_function("""() => [...document.querySelectorAll('#log li')]
        .some((li) => li.textContent.includes('Restoring'))""")
    assert page.locator("#command-error").text_content() == ""
    assert not errors
