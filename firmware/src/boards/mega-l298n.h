/* 1 m x 1 m plotter: Arduino Mega 2560, two NEMA 17 on L298N dual H-bridges
 * driven as four wires (bipolar), pen servo, a pause button; its limit
 * switches cut the motor supply, so the firmware never sees them. */
#ifndef BOARD_H
#define BOARD_H

#define BOARD_NAME "mega-l298n"
#define DRIVE_KIND DRIVE_BIPOLAR
/* full-step two-phase-on (1) or half-step (0):
 * make BOARD=mega-l298n EXTRA_CFLAGS=-DBIPOLAR_FULL_STEP=0 */
#ifndef BIPOLAR_FULL_STEP
#define BIPOLAR_FULL_STEP 1
#endif

/* L298N IN1..IN4 on 30, 32, 34, 36 (X) and 31, 33, 35, 37 (Y). The sequence
 * order is IN1, IN3, IN2, IN4: coil 1 forward, coil 2 forward, coil 1
 * reverse, coil 2 reverse. */
#define X_COIL_A C, 7   /* D30 IN1 */
#define X_COIL_B C, 3   /* D34 IN3 */
#define X_COIL_C C, 5   /* D32 IN2 */
#define X_COIL_D C, 1   /* D36 IN4 */
#define Y_COIL_A C, 6   /* D31 IN1 */
#define Y_COIL_B C, 2   /* D35 IN3 */
#define Y_COIL_C C, 4   /* D33 IN2 */
#define Y_COIL_D C, 0   /* D37 IN4 */

#define SERVO B, 4      /* D10 (edges set by the timer interrupt) */
#define BUTTON_PAUSE E, 4  /* D2, to ground: feed hold (resume with ~) */

#define BENCH_ISR F, 5  /* A5 */

/* 200 full steps/rev, GT2 20-tooth pulley: 5 steps/mm full, 10 half */
#define DEFAULT_STEPS_PER_MM (BIPOLAR_FULL_STEP ? 5.0f : 10.0f)
#define DEFAULT_MAX_RATE 6000.0f   /* mm/min: 500 full steps/s */
#define DEFAULT_ACCEL 500.0f       /* mm/s^2 */
#define DEFAULT_TRAVEL_X 1000.0f
#define DEFAULT_TRAVEL_Y 1000.0f
#define DEFAULT_HOMING 0           /* $20 $21 $22: switches not seen: boot Idle */
#define DEFAULT_BAUD 115200UL

#endif
