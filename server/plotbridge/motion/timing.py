"""Host-side timing of a plot: everything the estimate needs that is not the firmware's
motion code (which runs as itself, see library.py). In one place:

- Serial transfer: a line reaches the board `bytes * 10 / baud` seconds after the
  sender starts it (8N1: ten bits a byte), and the sender starts it only when the
  bytes of the lines not yet acknowledged plus its own fit the board's receive buffer
  (`rx_size`, character counting). A line is acknowledged once it is planned. Its
  bytes are those the server sends: the compact wire line (program/wire.py), with an
  `N` word where the board reports `Ln:` (`MachineProfile.line_numbers`: ours does,
  stock GRBL does not), counted by native/wirebytes.c.
- Per-line firmware time (`MachineProfile.plan_block_s`): from a line's last byte
  to its `ok` when the main loop was waiting for it and the planner has room (reading,
  parsing, planning, the `ok` going out; the step interrupt's share at plotting speed
  included); the next line is read only after it (and after any wait for planner
  room). Ours: `LINE_S`; stock GRBL: `GRBL_LINE_S`.
- Planner depth: how many blocks the board's planner holds (`MachineProfile.planner_blocks`).
- Pen moves and dwells wait for motion to stop, then `$62` ms (pen, only when it
  moves) or the dwell.

Segment timing (the step interrupt runs each segment's events at its period) and
everything about speeds comes from the firmware code itself.
"""

from __future__ import annotations

RX_SIZE = 128               # GRBL's receive buffer; both boards use it
GRBL_LINE_S = 0.0033        # stock GRBL 1.1 on a 328P (~300 short lines/s)
GRBL_PLANNER_BLOCKS = 15    # GRBL's BLOCK_BUFFER_SIZE 16 on a 328P, one kept free

# Our firmware's line time (firmware at eb724ca), measured by bench/line_time.py: the
# real firmware in a libsimavr harness streams compact wire lines with N words
# (`N123X112.34Y67.25`, ~18 bytes) slower than it takes them (a byte every 40-200 bit
# times), so each line meets an idle main loop; the figure is the median, over 1,200
# lines, of the simulated time from a line's last byte into the UART to the end of its
# `ok` (which includes the `ok`'s four bytes at 117,647 baud, 0.26 ms). It grows with
# the step rate (the step interrupt's share):
#   uno-cnc-shield (328P): 1.07 ms (0.2 mm at F1500), 1.08 (1 mm at F3000), 1.22
#     (0.2 mm at F6000), 1.23 (0.5 mm at F6000), 1.33 (0.5 mm at F12000)
#   mega-ramps14 (2560): 1.18, 1.20, 1.30, 1.32, 1.38 (its 3-byte return addresses and
#     larger planner)
# The figure used is the Uno's at F6000 (the default $110/$111) for every board: a
# board's `$I` names neither its chip nor its profile (the Mega's is ~6 % more). (On
# the wire a numbered line takes ~1.6 ms at 115200 baud, more than either board's
# line time, so the serial line paces dense drawings, not this figure.) The 2.2 ms
# before (measured on older firmware) made dense drawings' estimates too long.
LINE_S = 0.00122

