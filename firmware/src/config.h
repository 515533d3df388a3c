/* Build-time constants: buffer sizes, timing, and the selected board's header
 * (boards/NAME.h, the only place a pin is named). */
#ifndef CONFIG_H
#define CONFIG_H

#define FW_BANNER "Grbl 1.1h ['$' for help]"
#define FW_BUILD "[VER:1.1h.plotbridge:]"

#define N_AXIS 2
#define RX_SIZE 128          /* receive ring: GRBL's character-counting size */
#define TX_SIZE 128          /* transmit ring (power of two) */
#define LINE_SIZE 80         /* longest accepted line after stripping */
/* Planner ring: PLAN_SIZE - 1 usable blocks of 21 bytes (planner.h). Per
 * chip; the host library (make motion) takes the value of the board it is
 * built for from here. */
#ifndef PLAN_SIZE
#if defined(__AVR_ATmega2560__)
#define PLAN_SIZE 64         /* 63 blocks, 1.3 KiB: not more, because an override
                              * change re-derives every queued block's speed in
                              * one go (~5,000 cycles each) while the 7 prepared
                              * segments keep the steppers fed */
#else
#define PLAN_SIZE 34         /* 33 blocks, 693 B: 2 KiB less the stack's 512 B */
#endif
#endif
#define SEG_SIZE 8           /* step segment ring (7 usable) */

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

#endif
