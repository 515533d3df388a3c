/* Build-time constants: pins (DESIGN.md pin map), buffer sizes, timing. */
#ifndef CONFIG_H
#define CONFIG_H

#define FW_BANNER "Grbl 1.1h ['$' for help]"
#define FW_BUILD "[VER:1.1h.plotbridge:]"

#define N_AXIS 2
#define RX_SIZE 128          /* receive ring: GRBL's character-counting size */
#define TX_SIZE 128          /* transmit ring (power of two) */
#define LINE_SIZE 80         /* longest accepted line after stripping */
#define PLAN_SIZE 18         /* planner ring: 17 usable blocks (>= 16 look-ahead) */
#define SEG_SIZE 8           /* step segment ring (7 usable) */

/* Step timer: Timer1 at F_CPU/8 = 2 MHz. */
#define STEP_TIMER_HZ (F_CPU / 8UL)
#define STEP_PERIOD_MIN 40U  /* 50 kHz ceiling */
#define SEGMENT_S 0.008f     /* target duration of one step segment */

/* Port D: step and direction. */
#define X_STEP_BIT 2
#define Y_STEP_BIT 3
#define X_DIR_BIT 5
#define Y_DIR_BIT 6
#define STEP_MASK ((1 << X_STEP_BIT) | (1 << Y_STEP_BIT))
#define DIR_MASK ((1 << X_DIR_BIT) | (1 << Y_DIR_BIT))
/* Port B: enable (active low), limits, servo on OC2A. */
#define ENABLE_BIT 0
#define X_LIMIT_BIT 1
#define Y_LIMIT_BIT 2
#define SERVO_BIT 3
#define LIMIT_MASK ((1 << X_LIMIT_BIT) | (1 << Y_LIMIT_BIT))
/* Port C: buttons (active low) and the stop LED. */
#define ESTOP_BIT 0
#define PAUSE_BIT 1
#define RESUME_BIT 2
#define LED_BIT 3
#define BUTTON_MASK ((1 << ESTOP_BIT) | (1 << PAUSE_BIT) | (1 << RESUME_BIT))

#endif
