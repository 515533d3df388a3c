"""Firmware benchmark in simulated cycles (exact and repeatable).

Builds a bench variant of the firmware (-DBENCH_ISR_PIN: PC5 is high while
the step interrupt's body runs) and a small libsimavr harness
(firmware/test/bench/harness.c) that streams G-code into the UART with
character counting at the real byte rate and records acknowledgements, step
edges and the interrupt pin in simulated cycles. Measures:

- sustained two-axis step rate (45 degree move, 50 kHz commanded per axis),
  and whether any step came late (a 5 ms window below the commanded rate
  during the cruise);
- worst-case cycles of the step interrupt and of the interrupt that ends the
  pulse (the bench build raises PC4 for its body): the pin-measured body plus
  the fixed entry/exit cost counted from the disassembly;
- G-code throughput in lines per simulated second for 0.5 mm G1 segments in
  compact form (`X112.5Y67.25`: no spaces, modal G1 and F, no trailing
  zeros), at the acceleration of the target (3000 mm/s^2, where the
  planner's look-ahead caps it) and at 20000 mm/s^2 (where the CPU does);
  check-mode ($C) parsing of the same lines;
- flash and RAM use of the real build.

Each target is printed with its measured figure and MET / NOT MET, for each
board profile measured: uno-cnc-shield (ATmega328P) and mega-ramps14
(ATmega2560, the same 80 steps/mm; its bench build also raises PF4 for the
pulse-end interrupt).

Run: .venv/bin/python bench/firmware_bench.py [--board NAME ...]
     .venv/bin/python bench/firmware_bench.py --profile [--check | --accel A]
     (where the cycles of the CPU-bound throughput run, of the check-mode run,
     or with --accel of the F18000 run at A mm/s^2, go, per function, from
     program-counter samples)
     .venv/bin/python bench/firmware_bench.py --calls [--check | --accel A]
     (the same runs: every call counted, a line's calls and cycles from entry
     to return per called function and calling function, exact)
     .venv/bin/python bench/firmware_bench.py --before REF [--board NAME ...]
     (the same figures for the firmware of git commit REF first, built from
     its own sources in a temporary directory, then for the working tree's)
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FW = REPO / "firmware"
F_CPU = 16_000_000
TARGET_STEP_HZ = 50_000
TARGET_LINES_S = 600      # at 3000 mm/s^2 (the look-ahead's limit)
TARGET_LINES_CPU = 700    # CPU-bound
TARGET_CHECK = 1500       # $C check mode
CPU_ACCEL = 20_000  # mm/s^2: look-ahead then allows more than F24000 (400 mm/s)


@dataclass(frozen=True)
class Board:
    name: str
    mcu: str
    flash_max: int
    ram_max: int
    step_vector: str     # TIMER1_COMPA
    end_vector: str      # TIMER0_COMPA
    response: int        # cycles to enter an interrupt and to return (reti)
    pins: dict[str, str]  # harness pins: step X/Y, ISR body, pulse-end body
    extra_cflags: str = "-DBENCH_ISR_PIN"

    @property
    def build_dir(self) -> str:
        return "build" if self.name == "uno-cnc-shield" else f"build/{self.name}"


BOARDS = {
    "uno-cnc-shield": Board("uno-cnc-shield", "atmega328p", 30_720, 1_536, "__vector_11",
                            "__vector_14", 4, {}),
    # PF4 (A4) is free on the RAMPS; the 2560's 3-byte return address costs a cycle more
    "mega-ramps14": Board("mega-ramps14", "atmega2560", 253_952, 7_168, "__vector_17",
                          "__vector_21", 5,
                          {"HARNESS_STEP_X": "F0", "HARNESS_STEP_Y": "F6",
                           "HARNESS_ISR_PIN": "F5", "HARNESS_MARK_PIN": "F4"},
                          "-DBENCH_ISR_PIN -DBENCH_ISR_END=F,4"),
}


def run(cmd: list[str], **kw) -> str:
    return subprocess.run(cmd, check=True, capture_output=True, text=True, **kw).stdout


def build(board: Board, tmp: Path) -> tuple[Path, Path]:
    run(["make", "-s", "-C", str(FW), f"BOARD={board.name}", "all"])
    bench = f"{board.build_dir}/bench"
    run(["make", "-s", "-C", str(FW), f"BOARD={board.name}", f"BUILD={bench}",
         f"EXTRA_CFLAGS={board.extra_cflags}", f"{bench}/plotbridge.elf"])
    harness = tmp / "harness"
    cflags = run(["pkg-config", "--cflags", "simavr"]).split() if _has_pc("simavr") else []
    run(["gcc", "-O2", "-Wall", "-Wextra", "-I/usr/include/simavr", "-I/usr/include/simavr/avr",
         *cflags, str(FW / "test/bench/harness.c"), "-o", str(harness), "-lsimavr", "-lelf"])
    return FW / bench / "plotbridge.elf", harness


def planner_depth(board: Board) -> int:
    """Usable planner blocks of the board's build (config.h PLAN_SIZE - 1)."""
    return int(run(["make", "-s", "--no-print-directory", "-C", str(FW),
                    f"BOARD={board.name}", "print-BOARD_PLAN_SIZE"]).strip()) - 1


def _has_pc(name: str) -> bool:
    return subprocess.run(["pkg-config", "--exists", name]).returncode == 0


def simulate(harness: Path, elf: Path, lines: list[str], tmp: Path, max_s: float = 120,
             profile: Path | None = None, profile_from: int = 0,
             board: Board = BOARDS["uno-cnc-shield"], calls: Path | None = None,
             watch: list[int] | None = None) -> dict:
    gcode = tmp / "in.gcode"
    gcode.write_text("\n".join(lines) + "\n")
    env = {"HARNESS_PROFILE": str(profile),
           "HARNESS_PROFILE_FROM": str(profile_from)} if profile else {}
    if calls:
        env.update(HARNESS_CALLS=str(calls), HARNESS_PROFILE_FROM=str(profile_from),
                   HARNESS_CALLS_WATCH=",".join(str(a) for a in watch or []))
    env["HARNESS_SPAN_FROM"] = str(profile_from)
    env.update(board.pins, HARNESS_MCU=board.mcu)
    out = run([str(harness), str(elf), str(gcode), str(max_s)], env=env)
    result = json.loads(out[out.index("{"):])
    if result["errors"] or result["alarm"] or result["acked"] != result["lines"]:
        summary = {k: result[k] for k in ("lines", "acked", "errors", "alarm")}
        raise SystemExit(f"simulation went wrong: {summary}")
    return result


def isr_overhead_cycles(elf: Path, vector: str, response: int) -> int:
    """Entry/exit cost outside the pin-measured body: interrupt response and
    reti (4 each on the 328P, 5 on the 2560), the vector's jump (3), and the
    prologue/epilogue push/pop/in/out/eor."""
    dis = run(["avr-objdump", "-d", str(elf)])
    if f"<{vector}>:" not in dis:
        return 0  # a build without that interrupt (no pulse-end interrupt: a busy-wait)
    body = dis[dis.index(f"<{vector}>:"):]
    body = body[: body.index("reti") + 4]
    lines = body.splitlines()
    cycles = response + 3 + response
    for line in lines:
        m = re.search(r"\t(push|pop|in|out|eor|clr)\t", line)
        if m and ("r0" in line or "r1" in line or m.group(1) in ("push", "pop")):
            cycles += 2 if m.group(1) in ("push", "pop") else 1
    return cycles


def step_rate(harness: Path, elf: Path, tmp: Path, board: Board) -> dict:
    per_axis_mm_min = TARGET_STEP_HZ / 80 * 60  # 30000 mm/min at 80 steps/mm
    feed = per_axis_mm_min * math.sqrt(2)
    lines = ["$X", f"$110={per_axis_mm_min:.0f}", f"$111={per_axis_mm_min:.0f}", "$120=8000",
             "$121=8000", "$131=300", f"G1 X280 Y280 F{feed:.0f}"]
    r = simulate(harness, elf, lines, tmp, board=board)
    per_window = r["window_cycles"] / F_CPU
    rates = [(a / per_window, b / per_window) for a, b in r["windows"]]
    # the cruise: from the first window at the commanded rate (to within a
    # step: the window where the ramp ends is partly ramp) to the last one
    # near it; a late step shows up as a window inside the cruise that falls short
    start = next((i for i, (a, b) in enumerate(rates) if min(a, b) >= 0.995 * TARGET_STEP_HZ), None)
    cruise = [i for i, (a, b) in enumerate(rates) if a >= 0.97 * TARGET_STEP_HZ]
    inner = rates[start + 1: cruise[-1]] if start is not None else []
    late = sum(1 for a, b in inner if min(a, b) < 0.97 * TARGET_STEP_HZ)
    sustained = min(min(a, b) for a, b in inner) if inner else 0.0
    return {
        "sustained_hz_both_axes": sustained,
        "cruise_s": len(inner) * per_window,
        "late_windows": late,
        "steps": r["steps"],
        "isr_body_max_cycles": r["isr"]["max_cycles"],
        "isr_body_mean_cycles": r["isr"]["mean_cycles"],
        "end_body_max_cycles": r["mark"]["max_cycles"],
        "end_count": r["mark"]["count"],
        "period": r["period"],
        "min_step_interval_cycles": r["min_interval_cycles"],
    }


def circle_program(feed: float, check: bool, accel: float = 3000) -> tuple[list[str], list[str]]:
    """0.5 mm G1 segments around a circle of radius 50 mm, short modal lines."""
    r, n = 50.0, 1500
    per_turn = int(2 * math.pi * r / 0.5)
    # G4 P0 waits for the rapid to the start: without it the first acks come
    # at once (into the planner) and then wait for the rapid, which would be
    # counted against the line rate
    pre = ["$X", "$110=30000", "$111=30000", f"$120={accel:.0f}", f"$121={accel:.0f}",
           *(["$C"] if check else ["G0 X150 Y110", "G4 P0"]), f"G1 F{feed:.0f}"]
    body = []
    for k in range(1, n + 1):
        a = 2 * math.pi * k / per_turn
        body.append(f"X{compact(100 + r * math.cos(a))}Y{compact(110 + r * math.sin(a))}")
    return pre, body


def compact(v: float) -> str:
    """A coordinate as the compact stream sends it: two decimals (finer than a
    step at 80 steps/mm), no trailing zeros, no leading zero."""
    t = f"{v:.2f}".rstrip("0").rstrip(".")
    return t.replace("0.", ".", 1) if t.startswith(("0.", "-0.")) else t


def line_rates(harness: Path, elf: Path, tmp: Path, feed: float, check: bool,
               accel: float = 3000,
               board: Board = BOARDS["uno-cnc-shield"]) -> tuple[float, float]:
    """Lines/s acknowledged, and lines/s the CPU could do: the same lines over
    the time it was not asleep waiting for bytes (beyond the serial ceiling)."""
    pre, body = circle_program(feed, check, accel)
    res = simulate(harness, elf, pre + body, tmp, profile_from=len(pre), board=board)
    acks = res["ack_cycles"][len(pre):]
    span = acks[-1] - acks[0]
    busy = span - res["span_sleep_cycles"]
    return (len(acks) - 1) / (span / F_CPU), (len(acks) - 1) / (busy / F_CPU)


def lookahead_cap(accel: float, depth: int) -> float:
    """Lines/s of 0.5 mm segments the planner allows at best: it plans every
    queued block to a stop at the end of the queue, so the speed is at most
    sqrt(2 a L) over the blocks queued behind the one executing."""
    return math.sqrt(2 * accel * (depth - 1) * 0.5) / 0.5


def functions(elf: Path) -> list[tuple[int, int, str]]:
    """(byte address, size, name) of the image's functions, by address. The
    float library's assembly entries often have no size or a wrong one (one
    entry's size spans the next): a size runs at most to the next function,
    and an entry without one counts where no sized function covers it (not
    the local labels inside the assembly interrupts)."""
    sized, bare = [], []
    for line in run(["avr-nm", "-n", "-S", "-C", str(elf)]).splitlines():
        parts = line.split()
        if len(parts) in (3, 4) and parts[-2] in "tTW":
            (sized if len(parts) == 4 else bare).append((int(parts[0], 16), parts[-1], parts))
    syms = {a: (int(p[1], 16), name) for a, name, p in sized}
    for a, name, _ in bare:
        if a not in syms and not any(b <= a < b + size for b, (size, _) in syms.items()):
            syms[a] = (1 << 20, name)
    order = sorted(syms)
    return [(a, min(syms[a][0], nxt - a if nxt else syms[a][0]), syms[a][1])
            for a, nxt in zip(order, [*order[1:], None], strict=True)]


def function_at(funcs: list[tuple[int, int, str]], addr: int) -> str:
    return next((f for a, size, f in funcs if a <= addr < a + size), f"0x{addr:x}")


# jumped to, not called: no return address to count them by
NOT_CALLED = re.compile(r"__vector_\d+|__(prologue_saves|epilogue_restores|bad_interrupt)__|"
                        r"__(ctors|dtors)_\w+|__init|main|exit|_exit")


def call_profile(harness: Path, elf: Path, tmp: Path, feed: float = 24000,
                 accel: float = CPU_ACCEL, board: Board = BOARDS["uno-cnc-shield"],
                 check: bool = False) -> None:
    """Every call of every function in the profile's run, between the first
    and last ack: calls and cycles (entry to return, interrupts included) a
    line per called function, then per calling function under it."""
    pre, body = circle_program(feed, check, accel)
    out = tmp / "calls.txt"
    funcs = functions(elf)
    watch = [a for a, _, name in funcs if not NOT_CALLED.fullmatch(name)]
    res = simulate(harness, elf, pre + body, tmp, profile_from=len(pre), board=board,
                   calls=out, watch=watch)
    lines = len(res["ack_cycles"]) - len(pre) - 1
    per: dict[str, dict[str, list[int]]] = {}
    for row in out.read_text().split("\n"):
        if not row:
            continue
        callee, ret, n, cycles = (int(x) for x in row.split())
        caller = function_at(funcs, ret - 1)
        site = per.setdefault(function_at(funcs, callee), {}).setdefault(caller, [0, 0])
        site[0] += n
        site[1] += cycles
    print(f"{lines} lines: calls and cycles a line, from entry to return")
    total = {name: [sum(v[0] for v in c.values()), sum(v[1] for v in c.values())]
             for name, c in per.items()}
    for name, (n, cycles) in sorted(total.items(), key=lambda kv: -kv[1][1]):
        print(f"{cycles / lines:9.0f} {n / lines:7.2f}  {name}")
        for caller, (cn, cc) in sorted(per[name].items(), key=lambda kv: -kv[1][1]):
            print(f"{cc / lines:19.0f} {cn / lines:7.2f}    from {caller}")


def profile(harness: Path, elf: Path, tmp: Path, feed: float = 24000, accel: float = CPU_ACCEL,
            top: int = 25, board: Board = BOARDS["uno-cnc-shield"], check: bool = False) -> None:
    """Cycles per streamed line by function, between the first and last ack
    (the CPU-bound run, or with check the $C run; asleep: `(asleep)`)."""
    pre, body = circle_program(feed, check, accel)
    samples = tmp / "profile.txt"
    res = simulate(harness, elf, pre + body, tmp, profile=samples, profile_from=len(pre),
                   board=board)
    acks = res["ack_cycles"][len(pre):]
    funcs = functions(elf)
    counts: dict[str, int] = {}
    total = 0
    for line in samples.read_text().split("\n"):
        if not line:
            continue
        addr, n = (int(x) for x in line.split())
        name = function_at(funcs, addr)
        counts[name] = counts.get(name, 0) + n
        total += n
    # samples from the first streamed line's ack to the last one's
    per_sample = (acks[-1] - acks[0]) / total
    lines = len(acks) - 1
    print(f"{lines} lines at F{feed:.0f}: {(acks[-1] - acks[0]) / lines:.0f} cycles a line")
    for name, n in sorted(counts.items(), key=lambda kv: -kv[1])[:top]:
        print(f"{n * per_sample / lines:9.0f}  {name}")


def sizes(board: Board) -> dict:
    out = run(["avr-size", "-A", str(FW / board.build_dir / "plotbridge.elf")])
    sec = {m.group(1): int(m.group(2)) for m in re.finditer(r"^\.(\w+)\s+(\d+)", out, re.M)}
    return {"flash": sec["text"] + sec["data"], "ram": sec["data"] + sec["bss"]}


def verdict(ok: bool) -> str:
    return "MET" if ok else "NOT MET"


def measure(board: Board, tmp: Path) -> bool:
    """Prints the board's targets; True when all are met."""
    elf, harness = build(board, tmp)
    depth = planner_depth(board)
    overhead = isr_overhead_cycles(elf, board.step_vector, board.response)
    end_overhead = isr_overhead_cycles(elf, board.end_vector, board.response)
    sr = step_rate(harness, elf, tmp, board)
    _, body = circle_program(18000, False)
    serial_bytes = sum(len(b) + 1 for b in body) / len(body)
    serial_limit = 117_647 / 11 / serial_bytes  # the harness paces at 11 bits a byte
    lines_run = {f: line_rates(harness, elf, tmp, f, False, board=board)[0]
                 for f in (6000, 12000, 18000)}
    lines_check, check_cpu = line_rates(harness, elf, tmp, 18000, True, board=board)
    lines_cpu = line_rates(harness, elf, tmp, 24000, False, CPU_ACCEL, board)[0]
    sz = sizes(board)
    worst = sr["isr_body_max_cycles"] + overhead
    end_worst = sr["end_body_max_cycles"] + end_overhead if sr["end_count"] else 0
    period = F_CPU // TARGET_STEP_HZ
    results = []
    print(f"== {board.name} ({board.mcu}), planner {depth} blocks")

    def target(name: str, ok: bool, figure: str) -> None:
        results.append(ok)
        print(f"{verdict(ok):8} {name}: {figure}")

    target(f"step rate >= {TARGET_STEP_HZ} Hz on both axes, no late step",
           sr["sustained_hz_both_axes"] >= TARGET_STEP_HZ * 0.99 and sr["late_windows"] == 0,
           f"{sr['sustained_hz_both_axes']:.0f} Hz sustained over {sr['cruise_s']:.2f} s, "
           f"{sr['late_windows']} late 5 ms windows")
    # the busiest step period as measured: its tick, plus the pulse-end
    # interrupt when one ran in it (a tick that outlasts the pulse ends it itself)
    pd = sr["period"]
    alone = pd["worst_alone"] + overhead
    pair = (pd["worst_pair_isr"] + overhead + pd["worst_pair_mark"] + end_overhead
            if pd["worst_pair_mark"] else 0)
    target(f"step interrupts fit a {TARGET_STEP_HZ} Hz period ({period} cycles)",
           max(alone, pair) <= period,
           f"busiest period {max(alone, pair)} cycles (a tick alone: {alone}; a tick "
           f"and a pulse end: {pair}); step tick: body max {sr['isr_body_max_cycles']} / "
           f"mean {sr['isr_body_mean_cycles']:.0f} + {overhead} entry/exit = worst {worst} "
           f"cycles; pulse end: body max {sr['end_body_max_cycles']} + {end_overhead} = "
           f"worst {end_worst} cycles ({sr['end_count']} pulses ended by the timer "
           f"interrupt)")
    if end_overhead:
        print(f"         pulse end: Timer0 compare; {sr['end_count']} pulses ended by its "
              f"interrupt, the rest of {max(sr['steps'])} by the step interrupt on its way out "
              f"once the compare flag was set (its work outlasted the pulse): no busy-wait")
    else:
        print("         pulse end: busy-wait in the step interrupt (no pulse-end interrupt)")
    for f, v in lines_run.items():
        print(f"         0.5 mm G1 segments at F{f:.0f}: {v:.0f} lines/s (motion limit "
              f"{f / 60 / 0.5:.0f}, serial limit {serial_limit:.0f} at {serial_bytes:.1f} "
              f"bytes a line)")
    target(f"0.5 mm segments at 3000 mm/s^2 >= {TARGET_LINES_S} lines/s",
           max(lines_run.values()) >= TARGET_LINES_S,
           f"{max(lines_run.values()):.0f} lines/s "
           f"(look-ahead cap about {lookahead_cap(3000, depth):.0f})")
    target(f"0.5 mm segments CPU-bound (F24000, $120/$121={CPU_ACCEL}) "
           f">= {TARGET_LINES_CPU} lines/s",
           lines_cpu >= TARGET_LINES_CPU, f"{lines_cpu:.0f} lines/s (motion limit 800)")
    target(f"check mode ($C) >= {TARGET_CHECK} lines/s of CPU time", check_cpu >= TARGET_CHECK,
           f"{check_cpu:.0f} lines/s of CPU time ({F_CPU / check_cpu:.0f} cycles a line); "
           f"{lines_check:.0f} lines/s through the serial line (ceiling {serial_limit:.0f})")
    target(f"flash <= {board.flash_max} B", sz["flash"] <= board.flash_max, f"{sz['flash']} B")
    target(f"RAM (data+bss) <= {board.ram_max} B", sz["ram"] <= board.ram_max, f"{sz['ram']} B")
    return all(results)


def firmware_at(ref: str, tmp: Path) -> Path:
    """The firmware directory of git commit `ref`, extracted into tmp."""
    archive = subprocess.run(["git", "-C", str(REPO), "archive", ref, "firmware"], check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tmp)], input=archive, check=True)
    return tmp / "firmware"


def main() -> int:
    global FW
    args = sys.argv[1:]
    names = [args[k + 1] for k, a in enumerate(args[:-1]) if a == "--board"] or list(BOARDS)
    unknown = [n for n in names if n not in BOARDS]
    if unknown:
        raise SystemExit(f"unknown board {unknown[0]!r}: one of {', '.join(BOARDS)}")
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        if "--profile" in args or "--calls" in args:
            board = BOARDS[names[0]]
            elf, harness = build(board, tmp)
            accel = float(args[args.index("--accel") + 1]) if "--accel" in args else CPU_ACCEL
            feed = 18000 if "--accel" in args else 24000
            (profile if "--profile" in args else call_profile)(
                harness, elf, tmp, feed=feed, accel=accel, board=board, check="--check" in args)
            return 0
        if "--before" in args:
            ref = args[args.index("--before") + 1]
            here, FW = FW, firmware_at(ref, tmp)
            print(f"==== before: {ref}")
            for n in names:
                measure(BOARDS[n], tmp)
            FW = here
            print("==== after: the working tree")
        met = [measure(BOARDS[n], tmp) for n in names]
    print("all targets met" if all(met) else "SHORTFALL: see the figures above")
    return 0


if __name__ == "__main__":
    sys.exit(main())
