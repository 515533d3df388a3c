"""The job lifecycle (jobs/lifecycle.py): every (state, action) pair against the table, a
property test of random cause sequences, and through the real verbs (jobs/actions.py on a
fake board) that `actions` is exactly what the verbs accept."""

from __future__ import annotations

import random

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from plotbridge.errors import Refused
from plotbridge.jobs.imports import Importer
from plotbridge.jobs.lifecycle import ACTIONS, EVENTS, TABLE, State, allowed

from tests.fixtures.fake_app import fake_import, make_app, serving, upload
from tests.fixtures.jobs import a_job, lifecycle_with
from tests.fixtures.waits import settle

# The contract as /work/briefs/ACTIONS.md and docs/INTERNALS.md state it, written out again.
EXPECTED: dict[str, set[str]] = {
    "queued": {"start", "cancel", "frame", "move", "edit", "delete"},
    "waiting": {"cancel", "frame", "move", "delete"},
    "running": {"hold", "stop", "cancel"},
    "paused": {"continue", "stop", "cancel"},
    "pen_change": {"continue", "stop", "cancel"},
    "done": {"resume_from", "restart", "frame", "delete"},
    "failed": {"resume_from", "restart", "frame", "delete"},
    "cancelled": {"resume_from", "restart", "frame", "delete"},
    "stopped": {"resume", "home_then_resume", "resume_from", "restart", "cancel", "frame",
                "delete"},
    "interrupted": {"resume", "home_then_resume", "resume_from", "restart", "cancel", "frame",
                    "delete"},
    "awaiting_approval": {"approve", "decline", "cancel", "delete"},
}  # fmt: skip


@pytest.mark.parametrize("state", [s.value for s in State])
@pytest.mark.parametrize("action", ACTIONS)
def test_every_state_and_action_pair(state, action):
    job = a_job(state)
    life, _ = lifecycle_with(job)
    if action in EXPECTED[state]:
        life.check(job, action)  # allowed: no exception
        assert action in job.actions
    else:
        with pytest.raises(Refused) as refused:
            life.check(job, action)
        assert refused.value.status == 409
        assert refused.value.detail["state"] == state
        assert refused.value.detail["actions"] == job.actions
        assert action not in job.actions
    assert job.actions == [a for a in ACTIONS if a in EXPECTED[state]]  # in the fixed order


def test_a_move_persists_and_publishes_one_event_with_the_transition():
    job = a_job("queued")
    life, heard = lifecycle_with(job)
    life.move(job, "dispatch", plotter="p1")
    assert job.state == "running" and job.plotter == "p1"
    assert life.store.saved == [("j1", "running")]  # type: ignore[attr-defined]
    (message,) = heard
    assert message["transition"] == {"from": "queued", "to": "running", "cause": "dispatch"}
    assert message["job"]["actions"] == ["hold", "stop", "cancel"]


def test_a_move_the_table_does_not_have_is_a_bug_and_changes_nothing():
    job = a_job("done")
    life, heard = lifecycle_with(job)
    with pytest.raises(ValueError, match="no transition from done"):
        life.move(job, "hold")
    assert job.state == "done" and heard == []


async def test_a_claimed_job_refuses_every_other_action_and_offers_none():
    job = a_job("stopped")
    life, heard = lifecycle_with(job)
    async with life.claim(job, "home_then_resume"):
        assert job.actions == [] and heard[-1]["job"]["actions"] == []
        with pytest.raises(Refused) as refused:
            life.check(job, "resume")
        assert refused.value.status == 409 and "under way" in refused.value.detail["message"]
    assert job.actions == sorted(EXPECTED["stopped"], key=ACTIONS.index)


CAUSES = list(ACTIONS) + list(EVENTS)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.sampled_from(CAUSES), max_size=40))
def test_random_cause_sequences_stay_in_the_table(causes):
    """Whatever arrives, a job only ever takes the table's rows; an action is accepted
    exactly when it is in the job's `actions`."""
    job = a_job("queued")
    life, heard = lifecycle_with(job)
    for cause in causes:
        before = job.state
        offered = list(job.actions)
        if cause in ACTIONS:
            try:
                life.check(job, cause)
                accepted = True
            except Refused:
                accepted = False
            assert accepted == (cause in offered)
        key = (State(before), cause)
        if key in TABLE and TABLE[key] is not None:
            life.move(job, cause)
            assert job.state == TABLE[key]
            assert heard[-1]["transition"] == {"from": before, "to": job.state, "cause": cause}
        else:
            with pytest.raises(ValueError):
                life.move(job, cause)
            assert job.state == before
        assert job.actions == allowed(job.state)


# ---- through the verbs (jobs/actions.py) on the fake board ------------------------------


@pytest.fixture
async def api(tmp_path, monkeypatch):
    monkeypatch.setattr(Importer, "_import", fake_import)
    app, link = make_app(tmp_path)
    async with serving(app) as client:
        yield app.state.components, link, client


async def test_random_actions_through_the_verbs_match_actions(api):
    """A random walk of actions through `JobActions.act`: every refusal of an offered
    action is the plotter's (not the state's), every action not offered is refused with
    409 and the job's actions, and the job ends in a state of the table."""
    c, link, client = api
    link.auto_ack = False
    rng = random.Random(26)
    job_id = (await upload(client)).json()["id"]
    visited = set()
    for _ in range(150):
        job = c.queue.get(job_id)
        visited.add(job.state)
        offered = list(job.actions)
        action = rng.choice([a for a in ACTIONS if a not in ("delete", "edit", "move")])
        if rng.random() < 0.2:
            link.step()  # the board moves on by a line now and then
        body = {"from": {"line": 5}} if action == "resume_from" else None
        try:
            await c.actions.act(job_id, action, body=body)
        except Refused as exc:
            if action in offered:  # the machine refused it (Alarm after a stop): a string
                assert isinstance(exc.detail, str), (action, job.state, exc.detail)
            else:
                assert exc.status == 409 and exc.detail["actions"] == offered
                assert exc.detail["state"] == job.state
        else:
            assert action in offered, (action, job.state)
        if link.status.state == "Alarm" and rng.random() < 0.5:
            link.set_state("Idle", alarm=None)  # homed by hand
        await settle(lambda: c.queue.get(job_id).claim is None)
        assert c.queue.get(job_id).state in {s.value for s in State}
    assert len(visited) >= 5, visited  # the walk went through most of the life


async def test_refused_action_answers_409_with_state_and_actions_over_rest(api):
    _c, _link, client = api
    job = (await upload(client)).json()
    assert job["actions"] == ["start", "cancel", "frame", "move", "edit", "delete"]
    refused = await client.post(f"/api/jobs/{job['id']}/continue")
    assert refused.status_code == 409
    assert refused.json()["detail"] == {
        "message": f"job {job['id']} is queued: cannot continue it", "state": "queued",
        "actions": job["actions"]}  # fmt: skip
    unknown = await client.post(f"/api/jobs/{job['id']}/fly")
    assert unknown.status_code == 404 and "start" in unknown.json()["detail"]
