"""Importer benchmark: prints figures measured in this run, each with its target.

(a) import + validate + estimate throughput on a generated one-million-line G-code
    file, against a plain line count of the same file (target: within 10x);
(b) pen-up travel and time of our optimization against vpype's
    `linemerge linesort` on the same generated SVGs (target: travel no worse,
    time no slower);
(c) estimate against the simulated plot time on five drawings of different character,
    each uploaded to a real `plotbridge serve` on a virtual plotter at sim speed 1 and
    plotted by it: the job's estimate_s against the trace (target: within 2% each);
(d) SVG import speed per drawing (vpype's benchmark drawings from --vpype-drawings DIR,
    a checkout's tests/data/test_svg/benchmark; else generated ones of the same kinds and
    names, not vpype's files):
    our SVG stage (parse, resolve, flatten) against vpype's `read` (target: no slower),
    and our whole import (parse, optimize, estimate, preview) against vpype's
    `read linemerge linesort` (target: within 2x);
(e) inputs of the kinds that held an import worker (issue 32: path data that made a
    regular expression backtrack, long runs of digits before an error, unclosed CSS
    comments, G-code that made the dialect sniff quadratic), each beside vpype's `read`
    for the SVGs (target: each under 1 s).

Usage: python bench/import_bench.py [--lines N] [--skip a,b,c,d,e] [--sim-speed X]
                                    [--board NAME] [--vpype-drawings DIR]
"""

from __future__ import annotations

import argparse
import itertools
import math
import multiprocessing
import random
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from plotbridge.importing import (  # noqa: E402
    ImportOptions,
    MachineProfile,
    import_file,
)
from plotbridge.importing.detect import check_text, detect_format  # noqa: E402
from plotbridge.importing.gcode import sniff_dialect  # noqa: E402
from plotbridge.importing.models import ErrorLog, ImportFailed  # noqa: E402
from plotbridge.importing.optimize import optimize_strokes, time_budget  # noqa: E402
from plotbridge.importing.pipeline import SNIFF_CHARS  # noqa: E402
from plotbridge.importing.svg import read_svg  # noqa: E402
from plotbridge.motion import library  # noqa: E402

PX_MM = 25.4 / 96


# ---------------------------------------------------------------- (a) throughput

def write_big_gcode(path: Path, lines: int) -> None:
    """Random-walk strokes of 1 mm steps with comments and mixed feeds, ~50 bytes a line."""
    rng = random.Random(1)
    n = 2
    x, y = 150.0, 110.0
    with path.open("w") as f:
        f.write("G21\nG90\n")
        while n < lines:
            f.write(f"G0 X{x:.3f} Y{y:.3f}\nM3\n")
            n += 2
            for _ in range(min(200, lines - n - 1)):
                x = min(max(x + rng.uniform(-1, 1), 1), 299)
                y = min(max(y + rng.uniform(-1, 1), 1), 219)
                f.write(f"G1 X{x:.4f} Y{y:.4f} F{rng.choice((1500, 3000, 4500))} "
                        f"; stroke segment {n:07d}\n")
                n += 1
            f.write("M5\n")
            n += 1


def _stage_timers() -> dict[str, float]:
    """CPU seconds of the import's stages, each on the thread it runs on, summed while the
    import runs: the estimate's thread (the motion library), the scan's thread (reading
    the file and gcodescan.c), and on the importer's own thread movelines.c, the
    preview's simplification and preview.json. (Wrappers around the functions, for the
    bench only; each is called a few hundred times, so they cost nothing measurable.)"""
    from plotbridge.importing import gcode, preview, program
    from plotbridge.motion import estimate

    spent = dict.fromkeys(("motion", "scan", "movelines", "simplify", "preview.json"), 0.0)

    def timed(owner, name: str, stage: str) -> None:
        fn = getattr(owner, name)

        def wrapper(*args, **kwargs):
            t = time.thread_time()
            try:
                return fn(*args, **kwargs)
            finally:
                spent[stage] += time.thread_time() - t
        setattr(owner, name, wrapper)

    def timed_items(items):
        items = iter(items)
        while True:
            t = time.thread_time()
            item = next(items, None)
            spent["scan"] += time.thread_time() - t
            if item is None:
                return
            yield item

    ahead = gcode._ahead
    gcode._ahead = lambda items, depth=2: ahead(timed_items(items), depth)
    timed(estimate._Runner, "_work", "motion")
    timed(program.MoveLines, "run", "movelines")
    timed(preview.PreviewBuilder, "_simplify_pending", "simplify")
    timed(preview, "strokes_json", "preview.json")
    return spent


def _import_in_child(src: str, dest: str, queue) -> None:
    # The steps before the writer, each run on its own first (the file is then in the
    # page cache for the import, as it is for wc -l).
    start = time.process_time()
    encoding = check_text(Path(src))
    detect_format(Path(src), "big.gcode", encoding)
    with Path(src).open(encoding=encoding) as f:
        sniff_dialect(f.read(SNIFF_CHARS))
    checked = time.process_time() - start
    spent = _stage_timers()
    t = time.perf_counter()
    cpu = time.process_time()
    main = time.thread_time()
    r = import_file(Path(src), "big.gcode", Path(dest), ImportOptions(), MachineProfile())
    took, cpu = time.perf_counter() - t, time.process_time() - cpu
    main = time.thread_time() - main
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    queue.put((took, cpu, main, r.estimate_s, rss, checked, spent))


def bench_throughput(tmp: Path, lines: int) -> None:
    src = tmp / "big.gcode"
    write_big_gcode(src, lines)
    size = src.stat().st_size / 1e6
    # the target's reference: a plain `wc -l` of the same file (best of three, warm cache)
    floor = math.inf
    for _ in range(3):
        t = time.perf_counter()
        out = subprocess.run(["wc", "-l", str(src)], capture_output=True, text=True, check=True)
        floor = min(floor, time.perf_counter() - t)
    count = int(out.stdout.split()[0])
    t = time.perf_counter()
    with src.open("r") as f:
        sum(1 for _ in f)
    py_count = time.perf_counter() - t
    queue: multiprocessing.Queue = multiprocessing.Queue()
    child = multiprocessing.get_context("fork").Process(
        target=_import_in_child, args=(str(src), str(tmp / "big"), queue))
    child.start()
    took, cpu, main, estimate, rss, checked, spent = queue.get()
    child.join()
    print(f"(a) {count} lines, {size:.1f} MB: wc -l {floor:.3f} s "
          f"({count / floor:,.0f} lines/s; a Python line count {py_count:.2f} s); "
          f"import+validate+estimate+preview {took:.2f} s "
          f"({count / took:,.0f} lines/s; CPU {cpu:.2f} s, the figure to compare on a busy "
          f"machine), peak RSS {rss:.0f} MB, estimate {estimate / 3600:.2f} h")
    ratio = took / floor
    print(f"    ratio {ratio:.1f}x wc -l (target <= 10x): {'MET' if ratio <= 10 else 'NOT MET'}; "
          f"CPU ratio {cpu / floor:.1f}x; vs a Python line count {took / py_count:.1f}x")
    print(f"    peak RSS {rss:.0f} MB (target < 150 MB): {'MET' if rss < 150 else 'NOT MET'}")
    motion, scan = spent["motion"], spent["scan"]
    own = main - spent["movelines"] - spent["simplify"] - spent["preview.json"] - checked
    print(f"    CPU by thread (three threads share the cores; on a quiet 2-core machine the "
          f"wall time is about the largest, or half the sum): the importer's own {main:.2f} s "
          f"({main / floor:.1f}x wc -l), the estimate's (the motion library: the firmware's "
          f"planner and segments, C) {motion:.2f} s, the file's reading and scan (gcodescan.c) "
          f"{scan:.2f} s")
    print(f"    the importer's own thread: checking the text, its format and pen dialect "
          f"{checked:.2f} s, movelines.c (program text, estimate rows, preview calls) "
          f"{spent['movelines']:.2f} s, the preview's simplification {spent['simplify']:.2f} s, "
          f"preview.json {spent['preview.json']:.2f} s, the rest (the reader's and the "
          f"writer's Python per chunk and per stroke, writing the program) {own:.2f} s")
    bench_motion_library(count)


def bench_motion_library(lines: int) -> None:
    """The estimate alone (each line's wire bytes, then the motion library) on the same
    number of short moves."""
    import numpy as np
    from plotbridge.motion.estimate import Estimator
    rng = np.random.default_rng(1)
    steps = rng.uniform(-1, 1, size=(lines, 2))
    pts = np.clip(np.cumsum(steps, axis=0) + np.array([150.0, 110.0]), 1, 219)
    kind = np.full(lines, library.LINE, np.uint8)
    xs, ys = pts[:, 0].astype(np.float32), pts[:, 1].astype(np.float32)
    feed = np.full(lines, 3000.0, np.float32)
    nbytes = np.full(lines, 28, np.uint16)
    e = Estimator(MachineProfile())
    t = time.process_time()    # CPU: it runs on the estimate's thread
    e.moves(kind, xs, ys, feed, nbytes)
    e.flush()
    took = time.process_time() - t
    print(f"    the estimate alone (wire bytes, motion library) on {lines:,} moves of one "
          f"feed: CPU {took:.2f} s "
          f"({lines / took:,.0f} moves/s, {took / lines * 1e9:.0f} ns a move)")


# ---------------------------------------------------------------- (b) vs vpype

def svg_doc(paths: list[str], w: float = 250, h: float = 180) -> str:
    body = "\n".join(f'<path d="{d}" fill="none" stroke="black"/>' for d in paths)
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}mm" height="{h}mm" '
            f'viewBox="0 0 {w} {h}">\n{body}\n</svg>\n')


def generated_svgs() -> dict[str, str]:
    rng = random.Random(7)
    lines = []
    for _ in range(3000):
        x, y = rng.uniform(10, 240), rng.uniform(10, 170)
        a = rng.uniform(0, math.tau)
        r = rng.uniform(1, 8)
        lines.append(f"M {x:.3f} {y:.3f} L {x + r * math.cos(a):.3f} {y + r * math.sin(a):.3f}")
    circles = []
    for _ in range(600):
        x, y, r = rng.uniform(15, 235), rng.uniform(15, 165), rng.uniform(1, 10)
        circles.append(f"M {x - r:.3f} {y:.3f} A {r:.3f} {r:.3f} 0 1 0 {x + r:.3f} {y:.3f} "
                       f"A {r:.3f} {r:.3f} 0 1 0 {x - r:.3f} {y:.3f}")
    hatch = [f"M {10 + k * 0.5:.3f} 10 L {10 + k * 0.5:.3f} 170" for k in range(460)]
    rng.shuffle(hatch)
    walks = []
    for _ in range(400):
        x, y = rng.uniform(20, 230), rng.uniform(20, 160)
        pts = []
        for _ in range(40):
            x = min(max(x + rng.uniform(-2, 2), 1), 249)
            y = min(max(y + rng.uniform(-2, 2), 1), 179)
            pts.append(f"{x:.3f} {y:.3f}")
        walks.append("M " + " L ".join(pts))
    return {"short lines": svg_doc(lines), "circles": svg_doc(circles),
            "shuffled hatch": svg_doc(hatch), "random walks": svg_doc(walks)}


def program_strokes(program: Path) -> list[list[tuple[float, float]]]:
    strokes: list[list[tuple[float, float]]] = []
    x = y = 0.0
    down = False
    for line in program.read_text().splitlines():
        if line == "M3":
            down = True
            strokes.append([(x, y)])
        elif line == "M5":
            down = False
        elif line[:3] in ("G0 ", "G1 "):
            w = {v[0]: float(v[1:]) for v in line.split()[1:3]}
            x, y = w["X"], w["Y"]
            if down:
                strokes[-1].append((x, y))
    return strokes


def between_strokes(strokes) -> float:
    return sum(math.dist(a[-1], b[0]) for a, b in itertools.pairwise(strokes))


def bench_vs_vpype(tmp: Path) -> None:
    import vpype_cli

    for name, text in generated_svgs().items():
        src = tmp / f"{name.replace(' ', '_')}.svg"
        src.write_text(text)
        t = time.perf_counter()
        r = import_file(src, src.name, tmp / f"out_{src.stem}", ImportOptions(),
                        MachineProfile(width=300, height=220))
        ours_t = time.perf_counter() - t
        strokes = program_strokes(r.program_path)
        ours = between_strokes(strokes)
        t = time.perf_counter()
        doc = vpype_cli.execute(f"read '{src}' linemerge linesort write '{tmp / 'vp.svg'}'")
        vp_t = time.perf_counter() - t
        vp_travel = sum(lc.pen_up_length()[0] for lc in doc.layers.values()) * PX_MM
        vp_lines = sum(len(lc) for lc in doc.layers.values())
        # The optimization steps alone, on drawings already read.
        drawn = [s for lay in read_svg(src, ImportOptions(), ErrorLog()) for s in lay.strokes]
        t = time.perf_counter()
        optimize_strokes(drawn, 0.02, time.monotonic() + time_budget(len(drawn)))
        ours_opt = time.perf_counter() - t
        doc = vpype_cli.execute(f"read '{src}'")
        t = time.perf_counter()
        vpype_cli.execute("linemerge linesort", document=doc)
        vp_opt = time.perf_counter() - t
        print(f"(b) {name}: pen-up travel ours {ours:.1f} mm ({len(strokes)} strokes) vs "
              f"vpype {vp_travel:.1f} mm ({vp_lines}): ratio {ours / vp_travel:.2f} "
              f"[{'MET' if ours <= vp_travel * 1.0001 else 'NOT MET'}]")
        print(f"    time, whole pipeline: ours {ours_t:.2f} s (read, optimize, write program "
              f"and preview, estimate) vs vpype {vp_t:.2f} s (read, linemerge, linesort, "
              f"write): ratio {ours_t / vp_t:.2f} [{'MET' if ours_t <= vp_t else 'NOT MET'}]")
        print(f"    time, optimization only: ours {ours_opt:.3f} s vs vpype linemerge+linesort "
              f"{vp_opt:.3f} s: ratio {ours_opt / vp_opt:.2f} "
              f"[{'MET' if ours_opt <= vp_opt else 'NOT MET'}]")


# ------------------------------------------------------- (e) the slowest kinds of input

def hostile_inputs() -> dict[str, tuple[str, str]]:
    """Inputs of the kinds that held an import worker (issue 32): name -> (file name,
    text). Each is under 1 MB; the target is a time proportional to its size."""
    head = ('<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" '
            'viewBox="0 0 100 100">')
    redos = "M0 0" + "L10.5 10.5" * 40 + "A1 1 0 0 1 2 2"
    ruler = "M0 0" + "".join(f"L{k}.25 {k % 7}.5h.5v-1" for k in range(20_000)) + "a1 1 0 0 1 1 1"
    return {
        "issue 32's path": ("redos1.svg", head + f'<path stroke="black" fill="none" '
                                                 f'd="{redos}"/></svg>'),
        "issue 32's path (x2000)": ("redos.svg", head + "".join(
            f'<path stroke="black" fill="none" d="{redos}"/>' for _ in range(2000)) + "</svg>"),
        "one long path with an arc at its end": (
            "ruler.svg", head + f'<path stroke="black" fill="none" d="{ruler}"/></svg>'),
        "digits before a bad character": ("digits.svg", head + '<path stroke="black" d="M0 0L'
                                          + "1" * 500_000 + 'x"/><line x2="9" '
                                          'stroke="black"/></svg>'),
        "unclosed CSS comments and blocks": ("css.svg", head + "<style>" + "a{/*" * 100_000
                                             + "</style><line x2='9' stroke='black'/></svg>"),
        "60 KB of M3 lines (the laser sniff)": ("m3.gcode", "M3\n" * 20_000
                                                + "G0 X1 Y1\nM3\nG1 X5 Y5 F100\nM5\n"),
        "unclosed comments (G-code)": ("paren.gcode", "(" * 500_000
                                       + "\nG0 X1 Y1\nM3\nG1 X5 Y5 F100\nM5\n"),
    }


def bench_hostile(tmp: Path) -> None:
    import vpype_cli

    for name, (filename, text) in hostile_inputs().items():
        src = tmp / filename
        src.write_text(text)
        t = time.perf_counter()
        cpu = time.process_time()
        try:
            import_file(src, filename, tmp / f"out_{src.stem}", ImportOptions(fill="outline"),
                        MachineProfile(width=300, height=220))
            outcome = "imported"
        except ImportFailed as e:
            outcome = f"refused {e.status}: {e.errors[0]['message'][:40]}"
        ours = time.perf_counter() - t
        cpu = time.process_time() - cpu
        size = len(text.encode())
        line = (f"(e) {name}: {size / 1e6:.3f} MB, ours {ours:.2f} s, CPU {cpu:.2f} s "
                f"({outcome})")
        if filename.endswith(".svg"):
            t = time.perf_counter()
            try:
                vpype_cli.execute(f"read '{src}'")
                vp = f"{time.perf_counter() - t:.2f} s"
            except Exception as e:    # vpype's own refusal, named
                vp = f"fails after {time.perf_counter() - t:.2f} s ({type(e).__name__})"
            line += f" vs vpype read {vp}"
        print(line + f" [{'MET' if cpu < 1.0 else 'NOT MET'}: CPU under 1 s]")


# ---------------------------------------------------------------- (d) SVG import speed

def speed_drawings(tmp: Path, directory: Path | None) -> dict[str, Path]:
    """vpype's benchmark drawings when given, else generated drawings of the same kinds
    (quadratic and cubic Béziers, circles, long polylines, many short lines)."""
    if directory is not None:
        return {p.stem: p for p in sorted(directory.glob("*.svg"))}
    rng = random.Random(4)

    def pt() -> str:
        return f"{rng.uniform(0, 1000):.2f},{rng.uniform(0, 700):.2f}"

    kinds = {
        "900_quad_beziers": [f'<path d="M {pt()} Q {pt()} {pt()}"/>' for _ in range(900)],
        "300_beziers": [f'<path d="M {pt()} C {pt()} {pt()} {pt()}"/>' for _ in range(300)],
        "500_circles": [f'<circle cx="{rng.uniform(0, 1000):.1f}" cy="{rng.uniform(0, 700):.1f}" '
                        f'r="{rng.uniform(1, 50):.1f}"/>' for _ in range(500)],
        "500_polylines": ['<polyline points="' + " ".join(pt() for _ in range(400)) + '"/>'
                          for _ in range(500)],
        "7k_lines": [f'<line x1="{rng.uniform(0, 1000):.1f}" y1="{rng.uniform(0, 700):.1f}" '
                     f'x2="{rng.uniform(0, 1000):.1f}" y2="{rng.uniform(0, 700):.1f}"/>'
                     for _ in range(7000)],
        # long polylines written as path data (an Inkscape export)
        "bar_nodef_path_polylines": ['<path d="M ' + " L ".join(pt() for _ in range(600))
                                     + '"/>' for _ in range(175)],
        # many short curved paths in transformed groups (a traced drawing)
        "multi_skull": [f'<g transform="translate({rng.uniform(0, 500):.1f} '
                        f'{rng.uniform(0, 300):.1f}) scale(0.5)">'
                        + "".join(f'<path d="M {pt()} C {pt()} {pt()} {pt()} '
                                  f'S {pt()} {pt()} Z"/>' for _ in range(40)) + "</g>"
                        for _ in range(60)],
    }
    out = {}
    for name, shapes in kinds.items():
        p = tmp / f"gen_{name}.svg"
        p.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="1000" height="700" '
                     'fill="none" stroke="black">' + "".join(shapes) + "</svg>")
        out[name] = p
    return out


def _best(fn, runs: int = 3) -> float:
    """Best wall time of a few runs (the machine is shared: the best is the least noisy)."""
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def bench_svg_speed(tmp: Path, directory: Path | None) -> None:
    import vpype_cli

    big = MachineProfile(width=10_000, height=10_000)
    for name, src in speed_drawings(tmp, directory).items():
        ours_read = _best(lambda src=src: read_svg(src, ImportOptions(), ErrorLog()))
        vp_read = _best(lambda src=src: vpype_cli.execute(f"read '{src}'"))
        ours_all = _best(lambda src=src: import_file(
            src, src.name, tmp / f"speed_{src.stem}", ImportOptions(), big))
        vp_all = _best(lambda src=src: vpype_cli.execute(f"read '{src}' linemerge linesort"))
        met = "MET" if ours_read <= vp_read else "NOT MET"
        print(f"(d) {name}: SVG stage ours {ours_read:.3f} s vs vpype read {vp_read:.3f} s: "
              f"ratio {ours_read / vp_read:.2f} [{met}]")
        met = "MET" if ours_all <= 2 * vp_all else "NOT MET"
        print(f"    whole import ours {ours_all:.3f} s vs vpype read linemerge linesort "
              f"{vp_all:.3f} s: ratio {ours_all / vp_all:.2f} (target <= 2) [{met}]")


# ---------------------------------------------------------------- (c) estimate vs plot

def accuracy_drawings(tmp: Path) -> dict[str, Path]:
    """Five drawings of different character as uploads."""
    out: dict[str, Path] = {}
    # Long straight lines: acceleration is a small part.
    p = tmp / "long.gcode"
    p.write_text("G0 X20 Y20\nM3\nG1 X200 Y20 F4000\nG1 X200 Y180\nG1 X20 Y180\nG1 X20 Y20\n"
                 "G1 X200 Y180\nM5\nG0 X200 Y20\nM3\nG1 X20 Y180 F4000\nM5\n")
    out["long lines"] = p
    # Arcs, cut into chords by the firmware.
    lines = []
    for k in range(1, 9):
        r = 5.0 * k
        lines += [f"G0 X{100 + r:.3f} Y100", "M3",
                  f"G3 X{100 - r:.3f} Y100 I{-r:.3f} J0 F6000",
                  f"G3 X{100 + r:.3f} Y100 I{r:.3f} J0", "M5"]
    p = tmp / "arcs.gcode"
    p.write_text("\n".join(lines) + "\n")
    out["arcs"] = p
    # A spiral of 0.2 mm segments: bounded by the planner's look-ahead.
    pts = []
    t = 0.0
    while t < 20 * math.pi:
        r = 2 + 0.25 * t
        pts.append(f"G1 X{100 + r * math.cos(t):.3f} Y{100 + r * math.sin(t):.3f} F6000")
        t += 0.2 / r
    p = tmp / "spiral.gcode"
    p.write_text("G0 X102 Y100\nM3\n" + "\n".join(pts) + "\nM5\n")
    out["tiny segments"] = p
    # Sharp zig-zag corners: junction deviation.
    zz = [f"G1 X{20 + k * 2}.000 Y{50 if k % 2 else 20}.000 F5000" for k in range(40)]
    p = tmp / "zigzag.gcode"
    p.write_text("G0 X20 Y20\nM3\n" + "\n".join(zz) + "\nM5\n")
    out["zig-zag"] = p
    # Many pen lifts: text (pen settle time).
    out["text"] = Path("pattern:text")
    return out


ATTEMPTS = 4     # runs of a drawing at most while the machine is busy
QUIET = 0.05     # a run counts when the simulator was off the CPU at most this share


def _plot_through_server(plotsim, tmp: Path, src: Path, speed: float, board: str,
                         firmware: Path) -> tuple[float, float, int, float]:
    """One drawing through a real `plotbridge serve` on a fresh virtual plotter of board
    profile `board` (its firmware build `firmware`) at (0, 0):
    uploaded, imported and estimated by the server for that board, then plotted. Returns
    (the estimate and the simulated plot time, as plot_time.estimate_and_plot gives them,
    the program's lines, the seconds the simulator was kept off the CPU meanwhile: it
    then runs faster than the wall clock to catch up, and the server's pace counts for
    less)."""
    from tests.fixtures.plot_time import estimate_and_plot, idle
    from tests.fixtures.server import running_server

    run = Path(tempfile.mkdtemp(prefix=f"{src.stem}-", dir=tmp))
    plotter = plotsim.Plotter(plotsim.PLOTSIM, firmware, run / "eeprom.bin", speed, (0.0, 0.0),
                              ("--board", board))
    plotter.start()
    try:
        with running_server(run / "server", ["--serial", plotter.port, "--board", board]) as server:
            idle(server)
            if str(src).startswith("pattern:"):
                r = server.client.post("/api/jobs", params={
                    "pattern": src.name.split(":")[1], "paper": "A5-landscape"})
                assert r.status_code == 201, r.text
                job = r.json()
            else:
                job = server.submit(src.read_text(), start=False)
            job = server.wait_job(job["id"], "queued", timeout=120)
            waited = plotter.cpu_wait()
            predicted, plotted = estimate_and_plot(server, plotter, job["id"], timeout=3600)
            waited = plotter.cpu_wait() - waited
    finally:
        plotter.cleanup()
    return predicted, plotted, job["lines_total"], waited


def bench_accuracy(tmp: Path, speed: float, board: str) -> None:
    """What a user sees: each drawing uploaded to a real server on a virtual plotter of
    board profile `board` at sim speed `speed` (1: real time, so the server's own
    streaming pace counts), its job's estimate against the simulated plot time from the
    trace."""
    try:
        import pytest

        from tests.fixtures import plotsim
    except ImportError as e:
        print(f"(c) NOT MEASURED: {e}")
        return
    try:
        plotsim._make("-C", "firmware/sim")
        firmware = plotsim.board_firmware(board)
    except (Exception, pytest.fail.Exception) as e:  # the build prints its own output
        print(f"(c) NOT MEASURED: firmware or simulator does not build: {e}")
        return
    profile = MachineProfile.for_board({}, "1.1h.plotbridge", board)
    rev = subprocess.run(["git", "log", "-1", "--format=%h %s", "--", "firmware/src"], cwd=REPO,
                         capture_output=True, text=True).stdout.strip()
    depth = profile.planner_blocks or library.planner_depth(board)
    print(f"(c) firmware: {rev or 'unknown'}; board {board}; through `plotbridge serve` at "
          f"sim speed {speed:g}; planner model: {depth} blocks, "
          f"{profile.plan_block_s * 1000:.2f} ms to parse and plan a line, {profile.baud} "
          f"baud, compact wire lines "
          f"{'with' if profile.line_numbers else 'without'} N words "
          f"(the firmware's own motion code via libmotion)")
    for name, src in accuracy_drawings(tmp).items():
        # At sim speed 1 the server's pace counts: a simulator kept off the CPU (a busy
        # machine) runs faster than the wall clock to catch up, and a dense drawing then
        # waits for lines it would have had. Such a run is repeated (up to ATTEMPTS),
        # and the one with the simulator longest on the CPU is reported.
        runs = []
        for _ in range(ATTEMPTS):
            try:
                runs.append(_plot_through_server(plotsim, tmp, src, speed, board, firmware))
            except AssertionError as e:
                print(f"(c) {name:14s} NOT MEASURED: {e}")
                break
            if runs[-1][3] <= QUIET * runs[-1][1]:
                break
        if not runs:
            continue
        predicted, measured, lines, waited = min(runs, key=lambda r: r[3] / r[1])
        err = (predicted - measured) / measured
        print(f"(c) {name:14s} {lines:6d} lines: predicted {predicted:8.2f} s, plotted "
              f"{measured:8.2f} s (simulated): error {err * 100:+.2f}% "
              f"[{'MET' if abs(err) <= 0.02 else 'NOT MET'}] (simulator off the CPU "
              f"{waited:.2f} s{'' if waited <= QUIET * measured else ': a busy machine'}; "
              f"run {len(runs)} of {ATTEMPTS} at most)")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lines", type=int, default=1_000_000)
    ap.add_argument("--skip", default="")
    ap.add_argument("--sim-speed", type=float, default=1.0,
                    help="virtual plotter speed for (c); 1 keeps the sender realistic")
    ap.add_argument("--board", default=library.DEFAULT_BOARD,
                    help="board profile of (c)'s virtual plotter (firmware/src/boards/NAME.h)")
    ap.add_argument("--vpype-drawings", type=Path, default=None,
                    help="vpype's benchmark drawings for (d) (default: generated ones)")
    args = ap.parse_args()
    skip = set(args.skip.split(","))
    with tempfile.TemporaryDirectory(prefix="import-bench-") as d:
        tmp = Path(d)
        if "a" not in skip:
            bench_throughput(tmp, args.lines)
        if "b" not in skip:
            bench_vs_vpype(tmp)
        if "c" not in skip:
            bench_accuracy(tmp, args.sim_speed, args.board)
        if "d" not in skip:
            bench_svg_speed(tmp, args.vpype_drawings)
        if "e" not in skip:
            bench_hostile(tmp)
    return 0


if __name__ == "__main__":
    sys.stdout.reconfigure(line_buffering=True)
    sys.exit(main())
