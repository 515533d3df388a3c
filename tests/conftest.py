"""Shared pytest configuration: the fixtures live in tests/fixtures/."""

import pytest

from tests.fixtures.artifacts import MEASUREMENTS

pytest_plugins = ["tests.fixtures.plotsim", "tests.fixtures.server", "tests.fixtures.grbl",
                  "tests.fixtures.mosquitto", "tests.fixtures.stock_grbl"]


def pytest_sessionstart(session: pytest.Session) -> None:
    """measurements.json holds this run's figures only: emptied once, by the controlling
    process (pytest-xdist workers start sessions of their own)."""
    if not hasattr(session.config, "workerinput"):
        MEASUREMENTS.unlink(missing_ok=True)
