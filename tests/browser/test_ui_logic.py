"""The UI's pure functions, run in Chromium as the page runs them (ES modules from web/)."""

from __future__ import annotations

import json

import pytest

from tests.fixtures.pages import run, server_job

pytestmark = pytest.mark.browser


TWO_STROKES = (
    "m.buildGeometry({strokes: [[[0,0],[1,0],[2,0]], [[5,5],[6,5]]], travel: [[[2,0],[5,5]]]})"
)


def test_points_done_follows_the_normalized_program(modules):
    # header 3 lines; stroke 1: G0 M3 G1 G1 M5 (lines 4-8); stroke 2: G0 M3 G1 M5 (9-12); M5
    got = run(modules, f"""
        const g = {TWO_STROKES};
        const lines = [0, 4, 5, 6, 7, 8, 10, 11, 12, 13];
        return [g.expectedLines, ...lines.map((n) => m.pointsDone(g, n, 13))];
    """)
    assert got == [13, 0, 0, 1, 2, 3, 3, 4, 5, 5, 5]


def test_points_done_scales_when_the_program_has_more_lines_than_the_preview(modules):
    got = run(modules, f"""
        const g = {TWO_STROKES};
        return [m.pointsDone(g, 0, 1300), m.pointsDone(g, 650, 1300), m.pointsDone(g, 1300, 1300)];
    """)
    assert got[0] == 0 and 0 < got[1] < 5 and got[2] == 5


def test_refine_with_pen_finds_the_segment_under_the_pen(modules):
    got = run(modules, f"""
        const g = {TWO_STROKES};
        return [
          m.refineWithPen(g, 5, {{x: 1.5, y: 0}}),
          m.refineWithPen(g, 0, {{x: 5.5, y: 5.2}}),
          m.refineWithPen(g, 3, {{x: 3.5, y: 2.5}}),   // on the pen-up travel only
          m.refineWithPen(g, 3, null),
        ];
    """)
    assert got == [2, 4, None, None]


def test_paper_rect_and_placement_fields(modules):
    got = run(modules, """
        const f = m.placementFields(
          {paper: 'A4', landscape: true, margin: 5, fit: true, rotate: 90, scale: 2});
        return [
          m.paperRect({paper: 'A4-landscape'}), m.paperRect({paper: null}),
          m.paperRect({paper: 'letter'}), f, m.placementFromJob(f, {}),
          m.placementFields(
            {paper: '', landscape: true, margin: 10, fit: false, rotate: 0, scale: 1}),
        ];
    """)
    assert got[0] == {"x": 0, "y": 0, "w": 297, "h": 210}
    assert got[1] is None
    assert got[2] == {"x": 0, "y": 0, "w": 215.9, "h": 279.4}
    assert got[3] == {
        "paper": "A4-landscape", "margin": 5, "fit": True, "rotate": 90, "scale": 2,
        "dx": None, "dy": None,
    }
    assert got[4] == {
        "paper": "A4", "landscape": True, "margin": 5, "fit": True, "rotate": 90, "scale": 2,
        "dx": None, "dy": None,
    }
    assert got[5]["paper"] is None  # the work area: sent as null, so a PATCH clears it


def test_upload_errors_by_line(modules):
    got = run(modules, """
        const e = new (await import('/js/api.js')).ApiError(422,
          {errors: [{line: 4, message: "unsupported word E9"}, {line: null, message: "x"}]});
        return [m.uploadErrors(e), e.message];
    """)
    assert got[0] == [
        {"key": 0, "line": 4, "message": "unsupported word E9"},
        {"key": 1, "line": None, "message": "x"},
    ]
    assert got[1] == "line 4: unsupported word E9; x"


def test_banners_say_what_clears_them(modules):
    got = run(modules, """
        const s = m.initialState();
        const keys = (st) => m.bannersFor(st).map((b) => [b.key, b.actions.map((a) => a.action)]);
        const out = [keys(s)];
        s.socket.status = 'open';
        s.machine = {connected: true, state: 'Alarm', alarm: 3};
        out.push(keys(s), m.bannersFor(s)[0].text);
        s.machine = {connected: false, state: 'Disconnected'};
        out.push(keys(s));
        s.machine = {connected: true, state: 'Idle'};
        s.jobs = [JOB];
        out.push(keys(s));
        return out;
    """.replace("JOB", json.dumps(server_job("interrupted", id="a"))))
    assert got[0] == [["socket", ["reconnect"]]]
    assert got[1] == [["alarm", ["home", "unlock"]]]
    assert "position is probably lost" in got[2]
    assert got[3] == [["link", []]]
    want = [a for a in ("resume", "home_then_resume") if a in server_job("interrupted")["actions"]]
    assert got[4] == [["int-a", want]]


STATES = ["queued", "waiting", "running", "paused", "pen_change", "done", "failed", "cancelled",
          "stopped", "interrupted"]


def test_job_buttons_are_exactly_the_servers_actions(modules):
    jobs = [server_job(state) for state in STATES]
    got = run(modules, f"""
        const jobs = {json.dumps(jobs)};
        return jobs.map((j) => m.jobButtons(j, 0, 2).map((b) => b.verb + (b.disabled ? '-' : '')));
    """)
    for job, verbs in zip(jobs, got, strict=True):
        want = [a for a in job["actions"] if a not in ("edit", "move")]
        if "move" in job["actions"]:
            want += ["up-", "down"]
        assert verbs == want, job["state"]


def test_stop_confirmation_and_control_lock(modules):
    got = run(modules, """
        const s = m.initialState();
        s.machine = {connected: true, state: 'Run', seq: 5};
        s.jobs = [RUNNING];
        const out = [m.controlLock(s)];
        s.estop = {acked: false, seqAtClick: 5, wasMoving: true};
        out.push(m.estopConfirmed(s));
        s.estop.acked = true;
        out.push(m.estopConfirmed(s));          // still the report from before the click
        s.machine = {connected: true, state: 'Alarm', seq: 6};
        out.push(m.estopConfirmed(s));
        s.jobs = [STOPPED];
        out.push(m.controlLock(s));
        s.machine = {connected: true, state: 'Idle', seq: 7};
        out.push(m.controlLock(s));
        return out;
    """.replace("RUNNING", json.dumps(server_job("running", id="j")))
       .replace("STOPPED", json.dumps(server_job("stopped", id="j"))))
    assert got[0].startswith("Disabled while a job")
    assert got[1:4] == [False, False, True]
    assert got[4].startswith("In alarm")
    assert got[5] == ""


def test_hold_button_follows_the_selected_plotter(modules):
    got = run(modules, """
        const s = m.initialState();
        const out = [m.holdAction(s)];
        s.machine = {connected: true, state: 'Idle'};
        out.push(m.holdAction(s));
        s.machine.state = 'Jog';
        out.push(m.holdAction(s));
        s.machine.state = 'Hold';
        out.push(m.holdAction(s));
        s.machine.state = 'Idle';
        s.plotter = 'a';
        s.jobs = [{...RUNNING, plotter: 'b'}];
        out.push(m.holdAction(s));
        s.jobs[0].plotter = 'a';
        out.push(m.holdAction(s));
        s.jobs[0] = {...PAUSED, plotter: 'a'};
        out.push(m.holdAction(s));
        s.machine.connected = false;
        out.push(m.holdAction(s));
        return out;
    """.replace("RUNNING", json.dumps(server_job("running", id="j")))
       .replace("PAUSED", json.dumps(server_job("paused", id="j"))))
    assert got == [None, None, "hold", "continue", None, "hold", "continue", None]


def test_reducer_stop_from_another_page_and_its_end(modules):
    got = run(modules, """
        let s = {...m.initialState(), pageId: 'me', socket: {status: 'open'}};
        const before = s;
        s = m.reduce(s, {type: 'machine', plotter: 'p', machine: {connected: true, state: 'Run'}});
        const out = [before.machine, s.machine.seq, s.plotter];
        out.push(m.reduce(s, {type: 'stopped', plotter: 'p', origin: 'me'}).estop);  // ours
        s = m.reduce(s, {type: 'stopped', plotter: 'p', origin: 'other'});
        out.push(s.estop.remote, m.estopConfirmed(s));         // still moving: not yet
        const report = (state) =>
            ({type: 'machine', plotter: 'p', machine: {connected: true, state}});
        s = m.reduce(s, report('Alarm'));
        out.push(m.estopConfirmed(s), Boolean(s.estop));
        s = m.reduce(s, report('Idle'));
        out.push(s.estop);                                      // unlocked somewhere: gone
        s = m.reduce(s, {type: 'stopped', plotter: 'q', origin: 'other'});
        out.push(s.estop);                                      // another plotter's stop
        s = m.reduce(s, {type: 'stopped', plotter: 'p', origin: null});
        out.push(s.estop.remote);
        s = m.reduce(s, {type: 'job', job: RUNNING});
        out.push(s.estop);                                      // a job started: gone
        return out;
    """.replace("RUNNING", json.dumps(server_job("running", id="j"))))
    assert got[0] is None and got[1] == 1 and got[2] == "p"
    assert got[3] is None
    assert got[4:6] == ["browser", False]
    assert got[6:8] == [True, True]
    assert got[8] is None and got[9] is None
    assert got[10] == "client"
    assert got[11] is None


def test_reducer_jobs_and_the_shown_job(modules):
    got = run(modules, """
        let s = m.initialState();
        const name = (st) => (m.previewJob(st) || {}).id ?? null;
        const out = [];
        const J = JOBS;
        const jobs = [J.old, J.q];
        s = m.reduce(s, {type: 'jobs', jobs});
        out.push(name(s));                        // never the unrelated finished job
        s = m.reduce(s, {type: 'job', job: J.s});
        out.push(name(s));                        // a stopped job needs attention
        s = m.reduce(s, {type: 'job', job: J.qr});
        out.push(name(s));
        s = {...s, selectedJobId: 'old'};
        out.push(name(s));                        // the selected one wins
        s = m.reduce(s, {type: 'job_deleted', id: 'old'});
        s = m.reduce(s, {type: 'queue', order: ['s', 'q']});
        out.push(s.jobs.map((j) => j.id), name(s));
        s = m.reduce(s, {type: 'jobs', jobs: [J.d]});
        out.push(name(s));
        return out;
    """.replace("JOBS", json.dumps({
        "old": server_job("done", id="old"), "q": server_job("queued", id="q"),
        "s": server_job("stopped", id="s"), "qr": server_job("running", id="q"),
        "d": server_job("done", id="d"),
    })))
    assert got == [
        "q", "s", "q", "old", ["s", "q"], "q", None,
    ]


def test_reducer_placement_form_follows_its_job(modules):
    got = run(modules, """
        const job = (id, placement) => ({...QUEUED, id, placement});
        let s = m.initialState();
        s = m.reduce(s, {type: 'jobs', jobs: [job('a', {paper: 'A5-landscape', margin: 5, fit: true,
                                                            rotate: 90, scale: 2, dx: 3, dy: 4})]});
        const out = [s.placement];
        s = {...s, placement: {...s.placement, rotate: 180}, placementDirty: true};  // typing
        s = m.reduce(s, {type: 'job', job: {id: 'a', progress: 0}});
        out.push(s.placement.rotate);              // an edit in progress is kept
        s = {...s, placementDirty: false};
        s = m.reduce(s, {type: 'job', job: job('a', {paper: null, margin: 5, rotate: 270})});
        out.push([s.placement.paper, s.placement.rotate, s.placement.scale, s.placement.dx]);
        s = m.reduce(s, {type: 'job', job: job('b', {scale: 3})});
        s = {...s, selectedJobId: 'b'};
        s = m.withPlacement(s);
        out.push([s.placement.scale, s.placement.rotate, s.placementJob]);
        return out;
    """.replace("QUEUED", json.dumps(server_job("queued"))))
    assert got[0] == {
        "paper": "A5", "landscape": True, "margin": 5, "fit": True, "rotate": 90, "scale": 2,
        "dx": 3, "dy": 4,
    }
    assert got[1] == 180
    assert got[2] == ["", 270, 1, 0]
    assert got[3] == [3, 0, "b"]


def test_header_says_connection_lost(modules):
    got = run(modules, """
        const s = m.initialState();
        s.machine = {connected: true, state: 'Run', position: {x: 1, y: 2}, pen: 'down'};
        s.jobs = [{...RUNNING, progress: 0.5, eta_s: 120}];
        const live = m.headerSummary(s);
        s.serverLost = true;
        return [live, m.headerSummary(s)];
    """.replace("RUNNING", json.dumps(server_job("running", id="j"))))
    assert got[0]["state"] == "moving" and "left" in got[0]["job"] and got[0]["pos"]
    assert got[1] == {"state": "connection lost", "badge": "Lost", "pos": "", "pen": "", "job": ""}


def test_a_resume_with_the_layer_choice_and_its_websocket_message(modules):
    layers = [{"name": n, "first_line": f, "last_line": last, "label": n}
              for n, f, last in (("a", 1, 9), ("b", 11, 19), ("c", 21, 29))]  # fmt: skip
    job = server_job("stopped", id="j7", layers=layers,
                     done_point={"line": 12, "x": 1, "y": 2, "layer": 2})  # fmt: skip
    got = run(modules, f"""
        const job = {json.dumps(job)};
        const all = {{ticked: [1, 2, 3], start: null}};
        return [
          m.stoppedLayer(job), m.stoppedLayer({{...job, done_point: null, resume_line: 10}}),
          m.resumeChoice(job, all),                                  // where it stopped
          m.resumeChoice(job, {{ticked: [1, 2], start: null}}),     // without layer 3
          m.resumeChoice(job, {{ticked: [1, 3], start: null}}),     // skip the rest of 2
          m.resumeChoice(job, {{ticked: [1, 2, 3], start: 1}}),     // from layer 1 again
          m.resumeChoice(job, {{ticked: [1], start: null}}),        // nothing left
          m.actionMessage(job, "resume_from", {{body: {{from: {{layer: 3}}, layers: [1, 3]}}}}),
          m.actionMessage(job, "start", {{layers: {{ticked: [2, 3], start: 2}}}}),
          m.actionRequest(job, "delete"),
          m.layerRows(job, all).map((r) => [r.name, r.start, r.resumesHere]),
          m.layerTitle({{name: "#d40000", label: "red"}}, 2), m.layerTitle({{}}, 3),
        ];
    """)
    assert got[0] == 2 and got[1] == 2  # the M0 before layer 2 belongs to layer 2
    assert got[2] == {"action": "resume", "body": {}}
    assert got[3] == {"action": "resume", "body": {"layers": [1, 2]}}
    assert got[4] == {"action": "resume_from", "body": {"layers": [1, 3], "from": {"layer": 3}}}
    assert got[5] == {"action": "resume_from", "body": {"from": {"layer": 1}}}
    assert "no layer ticked from layer 2 on" in got[6]["error"]
    assert got[7] == {"type": "job_action", "job": "j7", "action": "resume_from",
                      "from": {"layer": 3}, "layers": [1, 3]}  # fmt: skip
    assert got[8] == {"type": "job_action", "job": "j7", "action": "start", "layers": [2, 3],
                      "start_layer": 2}  # fmt: skip
    assert got[9] == {"method": "DELETE", "path": "/api/jobs/j7"}
    assert got[10] == [["a", False, False], ["b", True, True], ["c", False, False]]
    assert got[11:] == ["red", "layer 3"]
