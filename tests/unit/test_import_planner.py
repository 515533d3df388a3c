"""The estimate's planner simulation against hand-computed motion profiles."""

from __future__ import annotations

import math

import pytest
from plotbridge.importing import MachineProfile, eta
from plotbridge.importing.planner import Planner, Timeline, trapezoid_time

# 1000 mm/s², 100 mm/s max rate, junction deviation 0.02 mm; lines and blocks reach
# the planner without delay unless a test says otherwise.
P = MachineProfile(baud=0, plan_block_s=0.0, block_gap_s=0.0)


def run(moves, profile=P, start=(0.0, 0.0)):
    pl = Planner(profile, start)
    for n, (x, y, f) in enumerate(moves, 1):
        pl.move(n, x, y, f)
    pl.flush()
    return pl.time


def test_one_trapezoid():
    # 100 mm at 50 mm/s: 0.05 s (1.25 mm) to accelerate, the same to stop, 97.5 mm cruise.
    assert run([(100, 0, 3000)]) == pytest.approx(0.05 + 0.05 + 97.5 / 50)


def test_triangle_profile():
    # 2 mm at up to 100 mm/s never reaches it: peak sqrt(a·L) = 44.72 mm/s.
    assert run([(2, 0, 6000)]) == pytest.approx(2 * math.sqrt(1000 * 2) / 1000)


def test_right_angle_junction():
    # Corner at 90°: sin(θ/2) = √½; the firmware takes the acceleration of the block
    # entered (1000 mm/s² along Y), so v² = 1000 · 0.02 · √½ / (1 - √½).
    s = math.sqrt(0.5)
    vj = math.sqrt(1000 * 0.02 * s / (1 - s))
    v = 10.0
    half = (v / 1000                     # accelerate from rest
            + (v - vj) / 1000            # slow to the corner speed
            + (10 - v * v / 2000 - (v * v - vj * vj) / 2000) / v)
    assert vj < v
    assert run([(10, 0, 600), (10, 10, 600)]) == pytest.approx(2 * half)


def test_straight_chain_runs_through_and_reversal_stops():
    assert run([(50, 0, 3000), (100, 0, 3000)]) == pytest.approx(run([(100, 0, 3000)]))
    there_and_back = run([(50, 0, 3000), (0, 0, 3000)])
    assert there_and_back == pytest.approx(2 * run([(50, 0, 3000)]))


def test_axis_limits_on_diagonals():
    slow_y = MachineProfile(max_rate=(6000, 3000), accel=(1000, 500), baud=0, plan_block_s=0,
                            block_gap_s=0)
    # Along 45°, each axis carries 1/√2 of the motion: Y limits speed to 50·√2 mm/s and
    # acceleration to 500·√2 mm/s².
    length = 100 * math.sqrt(2)
    expected = trapezoid_time(0, 0, 50 * math.sqrt(2), 500 * math.sqrt(2), length)
    assert run([(100, 100, 99999)], slow_y) == pytest.approx(expected)
    assert run([(100, 100, None)], slow_y) == pytest.approx(expected)


def test_short_segments_are_limited_by_the_buffer_depth():
    segs = [(0.1 * k, 0, 6000) for k in range(1, 1001)]
    deep = run(segs, MachineProfile(planner_blocks=100000, baud=0, plan_block_s=0, block_gap_s=0))
    assert deep == pytest.approx(run([(100, 0, 6000)]), rel=1e-6)
    # With 17 blocks the last 16 (1.6 mm) must suffice to stop: v² = 2·1000·1.6.
    v = math.sqrt(2 * 1000 * 1.6)
    shallow = run(segs)
    assert shallow == pytest.approx(100 / v + v / 1000, rel=0.01)


def test_arcs_are_cut_by_the_arc_tolerance():
    # Half circle r=2 at 100 mm/s: the fewest equal angles whose chords keep the sagitta
    # r(1 - cos(a/2)) within 0.002 mm, as the firmware cuts it.
    pl = Planner(P, start=(2.0, 0.0))
    pl.arc(1, -2.0, 0.0, -2.0, 0.0, 6000, False)
    pl.flush()
    n = math.ceil(math.pi / (2 * math.acos(1 - 0.002 / 2)))
    chords = [(2 * math.cos(math.pi * k / n), 2 * math.sin(math.pi * k / n), 6000)
              for k in range(1, n + 1)]
    assert n == 36
    assert pl.time == pytest.approx(run(chords, start=(2.0, 0.0)))
    assert pl.time > math.pi * 2 / 100 * 1.2   # the corners between chords slow it down


def test_pen_moves_and_dwell_stop_and_settle():
    pl = Planner(P)
    pl.move(1, 100, 0, 3000)
    pl.stop(2, P.pen_settle_s)
    pl.move(3, 200, 0, 3000)
    pl.flush()
    assert pl.time == pytest.approx(2 * run([(100, 0, 3000)]) + 0.15)


def test_timeline_thins_to_its_limit():
    t = Timeline(limit=10)
    for n in range(1, 1001):
        t.record(n, n * 0.5)
    samples = t.finish(1000, 500.0)
    assert len(samples) <= 10
    assert samples[-1] == (1000, 500.0)
    assert [s[0] for s in samples] == sorted(s[0] for s in samples)


def test_eta_interpolates():
    timeline = [(10, 5.0), (20, 15.0), (30, 20.0)]
    assert eta(timeline, 20.0, 0) == 20.0
    assert eta(timeline, 20.0, 15) == pytest.approx(10.0)
    assert eta(timeline, 20.0, 30) == 0.0
    assert eta([], 12.0, 3) == 12.0


def feed_lines(profile, lines, step=0.05):
    pl = Planner(profile)
    for n, text in enumerate(lines, 1):
        pl.receive(len(text) + 1)
        pl.move(n, step * n, 0.0, 6000)
    pl.flush()
    return pl.time


def test_serial_line_bounds_dense_short_moves():
    # 0.05 mm moves take ~1.3 ms each at the speed the look-ahead allows; their 23 bytes
    # take 2 ms at 115200 baud: the line sets the pace.
    lines = [f"G1 X{0.05 * k:.3f} Y0.000 F6000" for k in range(1, 2001)]
    fast = feed_lines(P, lines)
    slow = feed_lines(MachineProfile(plan_block_s=0, block_gap_s=0), lines)
    serial = sum(len(t) + 1 for t in lines) * 10 / 115200
    assert fast < serial
    assert slow == pytest.approx(serial, rel=0.06)
    # Long moves are not limited by the line: 100 mm takes 2 s, its 26 bytes 2.3 ms.
    pl = Planner(MachineProfile(plan_block_s=0, block_gap_s=0))
    pl.receive(26)
    pl.move(1, 100, 0, 3000)
    pl.flush()
    assert pl.time == pytest.approx(run([(100, 0, 3000)]) + 26 * 10 / 115200)


def test_firmware_planning_time_bounds_dense_short_moves():
    # 3.4 ms to plan each block is slower than the line (2 ms) and the motion (1.3 ms).
    lines = [f"G1 X{0.05 * k:.3f} Y0.000 F6000" for k in range(1, 2001)]
    cpu = feed_lines(MachineProfile(baud=0, plan_block_s=0.0034, block_gap_s=0), lines)
    assert cpu == pytest.approx(2000 * 0.0034, rel=0.05)
    both = feed_lines(MachineProfile(plan_block_s=0.0034, block_gap_s=0), lines)
    assert both == pytest.approx(cpu, rel=0.05)


def test_block_gap_adds_per_block():
    chain = [(0.4 * k, 0, 3000) for k in range(1, 301)]
    gap = MachineProfile(baud=0, plan_block_s=0.0, block_gap_s=0.001)
    assert run(chain, gap) == pytest.approx(run(chain) + 300 * 0.001)
