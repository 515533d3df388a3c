/* RAMPS 1.4 on an Arduino Mega 2560: X and Y driver sockets (A4988/DRV8825),
 * X/Y min and max endstops, the pen servo on the first servo header. */
#ifndef BOARD_H
#define BOARD_H

#define BOARD_NAME "mega-ramps14"
#define DRIVE_KIND DRIVE_STEPDIR

#define X_STEP F, 0     /* D54 (A0) */
#define X_DIR F, 1      /* D55 (A1) */
#define X_ENABLE D, 7   /* D38 */
#define Y_STEP F, 6     /* D60 (A6) */
#define Y_DIR F, 7      /* D61 (A7) */
#define Y_ENABLE F, 2   /* D56 (A2) */

#define X_MIN E, 5      /* D3 */
#define X_MAX E, 4      /* D2 */
#define Y_MIN J, 1      /* D14 */
#define Y_MAX J, 0      /* D15 */

#define SERVO B, 5      /* D11: servo header 1 (edges set by the timer interrupt) */

#define BENCH_ISR F, 5  /* A5 */

/* 1/16 microstepping, GT2 20-tooth pulley */
#define DEFAULT_STEPS_PER_MM 80.0f
#define DEFAULT_MAX_RATE 6000.0f   /* mm/min */
#define DEFAULT_ACCEL 1000.0f      /* mm/s^2 */
#define DEFAULT_TRAVEL_X 300.0f
#define DEFAULT_TRAVEL_Y 220.0f
#define DEFAULT_HOMING 1           /* $20 $21 $22 */
#define DEFAULT_BAUD 115200UL

#endif
