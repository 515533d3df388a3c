/* Drum plotter: Arduino Uno (ATmega328P), two 28BYJ-48 geared steppers on
 * ULN2003 boards (four coil wires each, unipolar half-step: 4096 half-steps
 * per output revolution), pen servo on D3, no switches, often an HC-06
 * Bluetooth serial module (9600 baud out of the box). */
#ifndef BOARD_H
#define BOARD_H

#define BOARD_NAME "uno-uln2003"
#define DRIVE_KIND DRIVE_UNIPOLAR

/* ULN2003 IN1..IN4 in the order the coils are energized */
#define X_COIL_A B, 0   /* D8  IN1 */
#define X_COIL_B B, 1   /* D9  IN2 */
#define X_COIL_C B, 2   /* D10 IN3 */
#define X_COIL_D B, 3   /* D11 IN4 */
#define Y_COIL_A C, 0   /* A0  IN1 */
#define Y_COIL_B C, 1   /* A1  IN2 */
#define Y_COIL_C C, 2   /* A2  IN3 */
#define Y_COIL_D C, 3   /* A3  IN4 */

#define SERVO D, 3      /* D3 (edges set by the timer interrupt) */

#define BENCH_ISR C, 5  /* A5 */

/* 4096 half-steps per turn; a 40 mm drum / pulley circumference: ~32.6/mm.
 * The 28BYJ-48 loses steps above ~1000 half-steps/s (15 rpm). */
#define DEFAULT_STEPS_PER_MM 32.6f
#define DEFAULT_MAX_RATE 1800.0f   /* mm/min: 980 half-steps/s */
#define DEFAULT_ACCEL 100.0f       /* mm/s^2 */
#define DEFAULT_TRAVEL_X 300.0f
#define DEFAULT_TRAVEL_Y 220.0f
#define DEFAULT_HOMING 0           /* $20 $21 $22: no switches: boot Idle */
#define DEFAULT_BAUD 9600UL        /* HC-06 factory setting */
/* 32 planner blocks, one fewer than the other Uno: this board's coil
 * driver keeps 18 B more RAM, and the line numbers (planner.h) leave no
 * room for it beside 33. The look-ahead is not what limits these motors:
 * from a stop to 1800 mm/min at 100 mm/s^2 takes 4.5 mm, 9 blocks of 0.5 mm. */
#define PLAN_SIZE 33

#endif
