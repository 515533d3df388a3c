"""The API fuzzed from its own OpenAPI schema (schemathesis) against a real server on the
virtual plotter: no request, however malformed, gets a 5xx, and answers match the schema."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import schemathesis
from hypothesis import HealthCheck, given, settings
from schemathesis.checks import (
    content_type_conformance,
    not_a_server_error,
    response_schema_conformance,
    status_code_conformance,
)

from tests.fixtures.server import ServerProcess, running_server


@pytest.fixture(scope="module")
def fuzz_server(tmp_path_factory) -> Iterator[ServerProcess]:
    data = tmp_path_factory.mktemp("fuzz") / "server-data"
    with running_server(data, ["--virtual", "--sim-speed", "0"]) as proc:
        yield proc


CHECKS = [
    not_a_server_error,
    status_code_conformance,
    content_type_conformance,
    response_schema_conformance,
]


@pytest.mark.e2e
@pytest.mark.timeout(600)
def test_api_never_fails_with_a_server_error(fuzz_server: ServerProcess):
    assert "swagger" in fuzz_server.client.get("/docs").text.lower()
    schema = schemathesis.openapi.from_url(f"{fuzz_server.url}/openapi.json")
    headers = {"Authorization": f"Bearer {fuzz_server.token}"}
    failures: dict[str, str] = {}
    operations = [result.ok() for result in schema.get_all_operations()]
    assert len(operations) >= 20, "the schema lost its endpoints"
    for operation in operations:

        @given(case=operation.as_strategy())
        @settings(max_examples=12, deadline=None, database=None,
                  suppress_health_check=list(HealthCheck))  # fmt: skip
        def call(case) -> None:
            case.call_and_validate(base_url=fuzz_server.url, headers=headers, checks=CHECKS)

        try:
            call()
        except (Exception, BaseExceptionGroup) as exc:  # report every operation, not the first
            failures[operation.label] = str(exc)[:2000]
    assert not failures, "\n\n".join(f"{label}:\n{text}" for label, text in failures.items())
