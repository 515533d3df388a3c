/* Build-time constants: buffer sizes, timing, and the selected board's header
 * (boards/NAME.h, the only place a pin is named). */
#ifndef CONFIG_H
#define CONFIG_H

#define FW_BANNER "Grbl 1.1h ['$' for help]"
#define FW_VERSION "[VER:1.1h.plotbridge:" /* then the $I= string and "]" */

#define N_AXIS 2
#define RX_SIZE 128          /* receive ring: GRBL's character-counting size */
/* Transmit ring (a power of two). The 328P's is 64 B: the 64 B it gives up
 * hold the line numbers of its 33 planner blocks (planner.h). A status
 * report while plotting is about 65 B, and the ring drains while the report
 * is formatted, so the main loop seldom waits on it, and then ~1 ms at
 * 115200 baud (87 us a byte); longer answers ($$, $#) wait as they always did. */
#if defined(__AVR_ATmega328P__)
#define TX_SIZE 64
#else
#define TX_SIZE 128
#endif
#define LINE_SIZE 80         /* the line buffer (and an EEPROM line) */
#define LINE_MAX 79          /* longest accepted line after stripping: GRBL's 80-byte buffer less its NUL */
#define SEG_SIZE 8           /* step segment ring (7 usable) */

/* GRBL rows that need more flash than the 328P has beside the pen features
 * (GRBL's own config.h leaves rows out the same way). Each is 1 on the 2560
 * and in the host builds; the 328P profiles leave them out unless the
 * build says otherwise (EXTRA_CFLAGS=-DGRBL_WCS=1 ...; the size check
 * fails if it does not fit). firmware/README.md lists what each costs.
 *  GRBL_WCS:   G54-G59 and G28/G30 positions in EEPROM, G10 L2/L20, G28.1, G30.1,
 *              $RST=# (without: G54 only, G28/G30 go to machine 0; error:20)
 *  GRBL_LINES: $N0/$N1 startup lines and the $I= build info string (error:3)
 *  GRBL_G93:   inverse time feed (error:20)
 * Line numbers (GRBL's USE_LINE_NUMBERS, OPT letter N: every planner block
 * keeps its line's N number, the status report shows the executing one as
 * |Ln:) are no option: every board has them. */
#if defined(__AVR_ATmega328P__)
#define GRBL_FULL_DEFAULT 0
#else
#define GRBL_FULL_DEFAULT 1
#endif
#ifndef GRBL_WCS
#define GRBL_WCS GRBL_FULL_DEFAULT
#endif
#ifndef GRBL_LINES
#define GRBL_LINES GRBL_FULL_DEFAULT
#endif
#ifndef GRBL_G93
#define GRBL_G93 GRBL_FULL_DEFAULT
#endif

/* Step timer: Timer1 at F_CPU/8 = 2 MHz. */
#define STEP_TIMER_HZ (F_CPU / 8UL)
#define STEP_PERIOD_MIN 40U  /* 50 kHz ceiling */
#define SEGMENT_S 0.008f     /* target duration of one step segment */

/* Drive kinds (the board header picks one as DRIVE_KIND). */
#define DRIVE_STEPDIR 1      /* step/dir drivers (A4988, DRV8825, TMC in step mode) */
#define DRIVE_UNIPOLAR 2     /* four coils, half-step 8-state (ULN2003 + 28BYJ-48) */
#define DRIVE_BIPOLAR 3      /* two H-bridges as four wires (L298N, L293D) */

/* The board: its pins and defaults (make BOARD=NAME picks the header). */
#ifndef BOARD_HEADER
#define BOARD_HEADER "boards/uno-cnc-shield.h"
#endif
#include "io.h"
#include BOARD_HEADER

/* Planner ring: PLAN_SIZE - 1 usable blocks of 24 bytes (planner.h). Per
 * chip unless the board header sets it; the host library (make motion)
 * takes the value of the board it is built for from here. */
#ifndef PLAN_SIZE
#if defined(__AVR_ATmega2560__)
#define PLAN_SIZE 64         /* 63 blocks, 1.5 KiB (an override change re-derives
                              * the queue's speeds 4 blocks per main-loop pass,
                              * so depth no longer starves the steppers then) */
#else
#define PLAN_SIZE 34         /* 33 blocks, 792 B: what 2 KiB less the stack's 512 B holds */
#endif
#endif
/* The 2560 (and the host library) keep each queued block's float geometry
 * (plan_motion_t, 16 B a block: 1 KiB for 63) beside the ring, so the
 * segment preparer does not derive it a second time (a square root, a
 * division and ~8 multiplies a block; the bench's CPU-bound 0.5 mm lines on
 * mega-ramps14 went from 420 to 463 a second with it). The 328P has no RAM
 * for it and derives it again. Either way the values are the same. */
#if defined(__AVR_ATmega328P__)
#define PLAN_CACHE_MOTION 0
#else
#define PLAN_CACHE_MOTION 1
#endif

#endif
