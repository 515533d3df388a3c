"""The estimate's bytes on the wire (native/wirebytes.c) against the compactor itself
(program/wire.py): line for line over random programs, and over a real import."""

from __future__ import annotations

import random

import numpy as np
import pytest
from plotbridge.importing import ImportOptions, MachineProfile, import_file
from plotbridge.motion import estimate
from plotbridge.native.wirebytes import WireBytes
from plotbridge.program.wire import Compactor, compact, numbered, plain

HEADS = ("G0", "G1", "G2", "G3")
OTHER = ("M3", "M5", "G4 P0.500", "M0", "G21", "G90", "G4 P0.000")


def coordinate(rng: random.Random) -> str:
    """3 decimals; often on a tie of the shorter texts' rounding (x.xx5, x.x50, x.500,
    eighths: exact in binary) and near zero (negative zero texts)."""
    m = rng.choice([rng.randint(-3000, 300_000), 5 * rng.randint(-60, 60_000),
                    125 * rng.randint(-8, 2400), 500 * rng.randint(-2, 600),
                    rng.randint(-20, 20)])
    return f"{m / 1000:.3f}"


def random_program(rng: random.Random, n: int, feeds: list[str]) -> list[str]:
    lines = []
    for _ in range(n):
        r = rng.random()
        if r < 0.45:
            lines.append(f"G1 X{coordinate(rng)} Y{coordinate(rng)} F{rng.choice(feeds)}")
        elif r < 0.6:
            lines.append(f"G0 X{coordinate(rng)} Y{coordinate(rng)}")
        elif r < 0.72:
            lines.append(f"{rng.choice(('G2', 'G3'))} X{coordinate(rng)} Y{coordinate(rng)} "
                         f"I{coordinate(rng)} J{coordinate(rng)} F{rng.choice(feeds)}")
        else:
            lines.append(rng.choice(OTHER))
    return lines


def arrays(lines: list[str]) -> tuple[np.ndarray, ...]:
    """The lines as the estimate holds them (float32 numbers, as its batches)."""
    n = len(lines)
    motion = np.full(n, 7, np.uint8)
    x, y, i, j, feed = (np.zeros(n, np.float32) for _ in range(5))
    keeps = np.zeros(n, np.uint8)
    nbytes = np.zeros(n, np.uint16)
    for k, text in enumerate(lines):
        head, *words = text.split()
        if head in HEADS:
            motion[k] = HEADS.index(head)
            v = {w[0]: float(w[1:]) for w in words}
            x[k], y[k], i[k], j[k], feed[k] = (v.get(c, 0.0) for c in "XYIJF")
        else:
            nbytes[k], keeps[k] = plain(text)
    return motion, x, y, i, j, feed, keeps, nbytes


def counted(lines: list[str], spm: tuple[float, float], numbers: bool,
            run: int = 777) -> np.ndarray:
    """WireBytes over the lines, in runs of `run` lines (the state goes on across runs)."""
    wire = WireBytes(spm, numbers)
    *a, nbytes = arrays(lines)
    for s in range(0, len(lines), run):
        wire.count(*(v[s:s + run] for v in a), nbytes[s:s + run])
    return nbytes.astype(np.int64)


def sent(lines: list[str], spm: tuple[float, float], numbers: bool) -> np.ndarray:
    c = Compactor(spm)
    out = [c.line(t) for t in lines]
    if numbers:
        out = [numbered(n, t) for n, t in enumerate(out, 1)]
    return np.array([len(t) + 1 for t in out])


@pytest.mark.parametrize("spm", [(80.0, 80.0), (100.0, 100.0), (78.74, 40.0), (200.0, 6.4)])
@pytest.mark.parametrize("numbers", [True, False])
def test_bytes_equal_the_compactors_line_for_line(spm, numbers):
    lines = random_program(random.Random(f"{spm}"), 4000,
                           ["3000", "1500", "1234.5", "99.9", "100", "60", "0.5"])
    assert np.array_equal(counted(lines, spm, numbers), sent(lines, spm, numbers))


@pytest.mark.parametrize("spm", [78.74, 100.0, 6.25, 157.48, 32.5])
def test_coordinates_a_half_step_from_a_step_round_as_python_rounds_them(spm):
    # m / 1000 * spm on (or a hair off) a half step: the C side's fast product must
    # hand these to Python's own operations
    ties = [m for m in range(-2000, 300_000) if abs((m * spm) % 1000 - 500) < 1e-6]
    assert len(ties) > 5
    lines = [f"G1 X{m / 1000:.3f} Y{ties[-1 - k] / 1000:.3f} F3000" for k, m in enumerate(ties)]
    assert np.array_equal(counted(lines, (spm, spm), True), sent(lines, (spm, spm), True))


def test_line_numbers_grow_a_digit_at_the_powers_of_ten():
    lines = ["G1 X1.000 Y1.000 F3000"] * 10_050
    got = counted(lines, (80.0, 80.0), True, run=4096)
    assert np.array_equal(got, sent(lines, (80.0, 80.0), True))
    assert got[9998] + 1 == got[9999]       # N9999 then N10000


def test_feeds_finer_than_a_tenth_differ_at_ties_by_an_f_word_at_most():
    # The estimate holds feeds as float32: a feed on a tie of the F text's rounding to
    # the tenth (F1000.05: the double is a hair above it, the float32 below) may be
    # taken to the other tenth, and its F word counted differently (a digit more or
    # less, sent or not); nothing else is.
    rng = random.Random(5)
    feeds = [f"{rng.uniform(50, 9000):.2f}" for _ in range(60)]
    lines = random_program(rng, 4000, feeds)
    diff = counted(lines, (80.0, 80.0), True) - sent(lines, (80.0, 80.0), True)
    f_word = 1 + max(map(len, feeds))
    assert np.abs(diff).max() <= f_word
    off = {lines[k].split("F")[-1] for k in np.flatnonzero(diff)}
    assert off and all(f.endswith("5") for f in off), off


def test_the_estimate_counts_what_the_server_sends(tmp_path, monkeypatch):
    """A real import (movelines.c's runs and the writer's own lines: pen changes,
    dwells, arcs): the bytes the estimate's batches carried into the library are the
    compact stream's of the program written, numbered or not."""
    src = tmp_path / "d.gcode"
    rng = random.Random(2)
    body = ["G21", "G90"]
    for k in range(60):
        body += [f"G0 X{rng.uniform(5, 200):.4f} Y{rng.uniform(5, 150):.4f}", "M3"]
        for _ in range(rng.randint(1, 30)):
            x, y = rng.uniform(5, 200), rng.uniform(5, 150)
            body.append(f"G1 X{x:.4f} Y{y:.4f} F{rng.choice((1500, 3000.25, 4500))}")
        if k % 7 == 0:      # a quarter circle from (x, y) about (x + 5, y + 5)
            body += [f"G2 X{x + 10:.4f} Y{y:.4f} I5 J5 F2000", "G4 P0.25"]
        body.append("M5")
    src.write_text("\n".join(body) + "\n")
    seen: list[np.ndarray] = []
    count = estimate._Batch.count_bytes

    def spy(batch, wire):
        count(batch, wire)
        seen.append(batch.bytes[:batch.n].copy())

    monkeypatch.setattr(estimate._Batch, "count_bytes", spy)
    monkeypatch.setattr(estimate, "BATCH", 256)     # several batches
    for numbers in (True, False):
        seen.clear()
        profile = MachineProfile(steps_per_mm=(78.74, 80.0), line_numbers=numbers)
        r = import_file(src, "d.gcode", tmp_path / f"out{numbers}", ImportOptions(), profile)
        program = r.program_path.read_text().splitlines()
        wire = [numbered(n, t) if numbers else t
                for n, t in compact(enumerate(program, 1), profile.steps_per_mm)]
        assert np.array_equal(np.concatenate(seen), [len(t) + 1 for t in wire])
        assert any(t.startswith(("G2", "G4")) for t in program)
