"""The estimate: the firmware's planner, arc and segment code built for the host
(libmotion) against hand-computed motion profiles and the host-side timing model.
Hand figures assume ideal trapezoids; the firmware's step segments come within 3%."""

from __future__ import annotations

import math

import numpy as np
import pytest
from plotbridge.importing import MachineProfile
from plotbridge.motion import estimate, library
from plotbridge.motion.estimate import Estimator, thin_timeline
from plotbridge.motion.eta import eta, share_done
from plotbridge.motion.timing import GRBL_PLANNER_BLOCKS
from plotbridge.program.wire import compact, numbered

# 1000 mm/s², 100 mm/s max rate, junction deviation 0.02 mm; lines reach the planner
# without delay unless a test says otherwise.
P = MachineProfile(baud=0, plan_block_s=0.0)


def trapezoid(v0, v1, vn, a, length):
    da, dd = (vn * vn - v0 * v0) / (2 * a), (vn * vn - v1 * v1) / (2 * a)
    if da + dd <= length:
        return (vn - v0) / a + (vn - v1) / a + (length - da - dd) / vn
    vp = math.sqrt((2 * a * length + v0 * v0 + v1 * v1) / 2)
    return (vp - v0) / a + (vp - v1) / a


def text(x, y, f=None):
    """A move's program line."""
    return f"G0 X{x:.3f} Y{y:.3f}" if f is None else f"G1 X{x:.3f} Y{y:.3f} F{f:g}"


def run(moves, profile=P):
    e = Estimator(profile)
    for n, (x, y, f) in enumerate(moves, 1):
        e.receive(text(x, y, f))
        e.move(n, x, y, f)
    e.flush()
    return e.time


def test_the_library_is_the_firmware_build():
    assert library.LIBRARY.name == "libmotion.so"
    assert library.load().motion_plan_size() >= 16


def test_each_board_build_has_that_boards_planner_depth():
    # the compact blocks: at least 30 on the 328P (was 17), more on the 2560 (was 33)
    uno, mega = library.planner_depth(), library.planner_depth("mega-ramps14")
    assert uno >= 30
    assert mega >= 60
    # a board deeper than its profile's build runs on the deepest build, a board deeper
    # than that with the deepest build's depth
    segs = [(0.1 * k, 0, 6000) for k in range(1, 1001)]
    times = [run(segs, MachineProfile(planner_blocks=n, baud=0, plan_block_s=0))
             for n in (uno, mega, 10 * mega)]
    assert times[0] > times[1] == times[2]


def test_one_trapezoid():
    assert run([(100, 0, 3000)]) == pytest.approx(trapezoid(0, 0, 50, 1000, 100), rel=0.005)


def test_triangle_profile():
    assert run([(2, 0, 6000)]) == pytest.approx(trapezoid(0, 0, 100, 1000, 2), rel=0.03)


def test_right_angle_junction():
    s = math.sqrt(0.5)
    vj = math.sqrt(1000 * 0.02 * s / (1 - s))
    half = trapezoid(0, vj, 10, 1000, 10)
    assert run([(10, 0, 600), (10, 10, 600)]) == pytest.approx(2 * half, rel=0.01)


def test_straight_chain_runs_through_and_reversal_stops():
    assert run([(50, 0, 3000), (100, 0, 3000)]) == pytest.approx(run([(100, 0, 3000)]),
                                                                   rel=0.005)
    assert run([(50, 0, 3000), (0, 0, 3000)]) == pytest.approx(2 * run([(50, 0, 3000)]),
                                                                rel=0.005)


def test_axis_limits_on_diagonals():
    slow_y = MachineProfile(max_rate=(6000, 3000), accel=(1000, 500), baud=0, plan_block_s=0)
    expected = trapezoid(0, 0, 50 * math.sqrt(2), 500 * math.sqrt(2), 100 * math.sqrt(2))
    assert run([(100, 100, 99999)], slow_y) == pytest.approx(expected, rel=0.005)
    assert run([(100, 100, None)], slow_y) == pytest.approx(expected, rel=0.005)


def test_short_segments_are_limited_by_the_planner_depth():
    segs = [(0.1 * k, 0, 6000) for k in range(1, 1001)]
    # With the board's depth queued (the oldest ones partly cut into step segments
    # already) the last depth-4 to depth-1 blocks (0.1 mm each) must suffice to stop:
    # v² = 2·1000·d. (depth - 1: the whole queue behind the block being prepared; the
    # stream's start, where the preparer waits for lines while few blocks are queued,
    # comes close to it.)
    def cruise(d):
        v = math.sqrt(2 * 1000 * d)
        return 100 / v + v / 1000
    depth = library.planner_depth()  # the default profile's: the board's own
    assert cruise((depth - 1) * 0.1) < run(segs) < cruise((depth - 4) * 0.1)
    shallow = MachineProfile(planner_blocks=4, baud=0, plan_block_s=0)
    # blocks already cut into step segments (up to 7 of 8 ms) no longer count
    assert cruise(0.6) < run(segs, shallow) < cruise(0.2)


def test_stock_grbl_uses_its_planner_depth_and_line_time():
    grbl = MachineProfile.stock_grbl({110: 6000, 111: 6000, 120: 1000, 121: 1000})
    assert grbl.planner_blocks == GRBL_PLANNER_BLOCKS
    segs = [(0.1 * k, 0, 6000) for k in range(1, 401)]
    ours = run(segs, MachineProfile())
    theirs = run(segs, grbl)
    # 400 lines at GRBL's 3.3 ms each: the CPU sets the pace
    assert theirs == pytest.approx(400 * grbl.plan_block_s, rel=0.05)
    assert theirs > ours


def test_arcs_are_cut_by_the_arc_tolerance():
    e = Estimator(P)
    e.receive(text(2, 0))
    e.move(1, 2.0, 0.0, None)
    e.receive("M3")
    e.stop(2, 0.0)
    e.receive("G3 X-2.000 Y0.000 I-2.000 J0.000 F6000")
    e.arc(3, -2.0, 0.0, -2.0, 0.0, 6000, False)
    e.flush()
    n = math.ceil(math.pi / (2 * math.acos(1 - 0.002 / 2)))
    assert n == 36
    chords = [(2, 0, None)] + [(2 * math.cos(math.pi * k / n), 2 * math.sin(math.pi * k / n),
                                6000) for k in range(1, n + 1)]
    # the same chords as G1 lines (after a stop at the start) take the same time
    e2 = Estimator(P)
    for k, (x, y, f) in enumerate(chords):
        e2.receive(text(x, y, f))
        e2.move(k, x, y, f)
        if k == 0:
            e2.receive("M3")
            e2.stop(1, 0.0)
    e2.flush()
    assert e.time == pytest.approx(e2.time, rel=1e-6)
    assert e.time > run([(2, 0, None)]) + math.pi * 2 / 100 * 1.2   # corners slow it


def test_pen_moves_and_dwell_stop_and_settle():
    e = Estimator(P)
    e.receive(text(100, 0, 3000))
    e.move(1, 100, 0, 3000)
    e.receive("M3")
    e.stop(2, P.pen_settle_s)
    e.receive(text(200, 0, 3000))
    e.move(3, 200, 0, 3000)
    e.flush()
    assert e.time == pytest.approx(2 * run([(100, 0, 3000)]) + 0.15, rel=0.005)


def dense(n=2000):
    """n moves of 0.05 mm along Y=0.123 at F6000 (on the wire `X12.05Y.12`)."""
    return [(0.05 * k, 0.123) for k in range(1, n + 1)]


def feed_lines(profile, points):
    e = Estimator(profile)
    for n, (x, y) in enumerate(points, 1):
        e.receive(text(x, y, 6000))
        e.move(n, x, y, 6000)
    e.flush()
    return e.time


def test_serial_line_bounds_dense_short_moves():
    # what goes over the serial line: the compact wire lines, numbered (`N241X12.05Y.12`)
    # or not. A slow line, and an acceleration so high that a move alone in the planner
    # (the line starves it) takes little longer than at full speed (~2 ms: the step
    # segments' granularity)
    points = dense()
    lines = [text(x, y, 6000) for x, y in points]
    quick = {"accel": (1e6, 1e6), "plan_block_s": 0}
    fast = feed_lines(MachineProfile(baud=0, **quick), points)
    for numbers in (True, False):
        slow = feed_lines(MachineProfile(line_numbers=numbers, baud=19200, **quick), points)
        sent = [numbered(n, t) if numbers else t
                for n, t in compact(enumerate(lines, 1), P.steps_per_mm)]
        serial = sum(len(t) + 1 for t in sent) * 10 / 19200
        assert fast < serial
        assert slow == pytest.approx(serial, rel=0.06)


def test_firmware_line_time_bounds_dense_short_moves():
    cpu = feed_lines(MachineProfile(baud=0, plan_block_s=0.0034), dense())
    assert cpu == pytest.approx(2000 * 0.0034, rel=0.05)


def test_timeline_thins_to_its_limit():
    ack = np.arange(1, 1001) * 0.5
    samples = thin_timeline(ack, 1000, 500.0, limit=10)
    assert len(samples) <= 10
    assert samples[-1] == (1000, 500.0)
    assert [s[0] for s in samples] == sorted(s[0] for s in samples)


def test_eta_interpolates():
    timeline = [(10, 5.0), (20, 15.0), (30, 20.0)]
    assert eta(timeline, 20.0, 0) == 20.0
    assert eta(timeline, 20.0, 15) == pytest.approx(10.0)
    assert eta(timeline, 20.0, 30) == 0.0
    assert eta([], 12.0, 3) == 12.0


def test_share_done_weighs_a_stretch_of_lines_by_its_estimated_time():
    timeline = [(10, 5.0), (20, 15.0), (30, 20.0)]
    assert share_done(timeline, 11, 20, 10) == 0.0
    assert share_done(timeline, 11, 20, 15) == pytest.approx(0.5)
    assert share_done(timeline, 11, 30, 20) == pytest.approx(10 / 15)  # time, not lines
    assert share_done(timeline, 11, 30, 30) == 1.0
    assert share_done([], 1, 4, 1) == 0.25  # no timeline: by lines


def _zigzag(e: Estimator, n: int) -> Estimator:
    kind = np.full(n, library.LINE, np.uint8)
    kind[::50] = library.RAPID
    x = (np.arange(n) % 7).astype(np.float32)
    y = (np.arange(n) % 5).astype(np.float32) * 0.5
    feed = np.where(kind == library.LINE, 3000.0, 0.0).astype(np.float32)
    e.receive("M3")
    e.stop(1, P.pen_settle_s)
    e.moves(kind, x, y, feed, np.full(n, 24, np.uint16))
    return e


def test_batches_run_as_one_program(monkeypatch):
    whole = _zigzag(Estimator(P), 5000)
    whole.flush()
    monkeypatch.setattr(estimate, "BATCH", 1000)    # 6 batches, the thread fed as it goes
    batched = _zigzag(Estimator(P), 5000)
    batched.flush()
    assert batched.time == whole.time
    assert np.array_equal(batched.ack, whole.ack) and len(whole.ack) == 5001


def test_a_closed_program_frees_the_library(monkeypatch):
    monkeypatch.setattr(estimate, "BATCH", 1000)
    dropped = _zigzag(Estimator(P), 5000)    # its thread holds the library
    dropped.close()
    assert library.run_lock.acquire(timeout=30)    # another estimate can run
    library.run_lock.release()


def test_a_library_failure_is_raised_by_flush(monkeypatch):
    def missing(board=library.DEFAULT_BOARD):
        raise library.MotionLibraryMissing("no libmotion")
    monkeypatch.setattr(estimate, "BATCH", 1000)
    monkeypatch.setattr(library, "load", missing)
    e = _zigzag(Estimator(P), 5000)    # more batches than the queue holds: none blocks
    with pytest.raises(library.MotionLibraryMissing):
        e.flush()
