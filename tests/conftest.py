"""Shared pytest configuration: the fixtures live in tests/fixtures/."""

pytest_plugins = ["tests.fixtures.plotsim", "tests.fixtures.server", "tests.fixtures.grbl"]
