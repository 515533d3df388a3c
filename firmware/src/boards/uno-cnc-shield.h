/* Arduino Uno (ATmega328P) with the CNC shield v3 and A4988/DRV8825 step/dir
 * drivers: the default profile. Pins as PORT, BIT (Arduino numbers in comments). */
#ifndef BOARD_H
#define BOARD_H

#define BOARD_NAME "uno-cnc-shield"
#define DRIVE_KIND DRIVE_STEPDIR

/* drivers: X socket, Y socket; one enable line for all (active low) */
#define X_STEP D, 2     /* D2 */
#define Y_STEP D, 3     /* D3 */
#define X_DIR D, 5      /* D5 */
#define Y_DIR D, 6      /* D6 */
#define X_ENABLE B, 0   /* D8: the shield has one enable line for all drivers */

/* one limit switch per axis, at the homing end ($23), to ground */
#define X_LIMIT B, 1    /* D9 */
#define Y_LIMIT B, 2    /* D10 */

/* buttons to ground, and the stop LED */
#define BUTTON_ESTOP C, 0  /* A0 */
#define BUTTON_PAUSE C, 1  /* A1 */
#define BUTTON_RESUME C, 2 /* A2 */
#define LED_STOP C, 3      /* A3 */

/* pen servo on OC2A: its edges come from the timer hardware */
#define SERVO B, 3      /* D11 */
#define SERVO_OC2A 1
/* switches and buttons act from pin-change interrupts: PCINT0 group
 * (port B: the switches), PCINT1 group (port C: the buttons) */
#define INPUTS_PCINT 1

/* bench builds raise these pins for the bodies of the step interrupts */
#define BENCH_ISR C, 5  /* A5 */
#define BENCH_ISR_END C, 4 /* A4: the step pulse's end interrupt */

/* defaults for $-settings */
#define DEFAULT_STEPS_PER_MM 80.0f
#define DEFAULT_MAX_RATE 6000.0f   /* mm/min */
#define DEFAULT_ACCEL 1000.0f      /* mm/s^2 */
#define DEFAULT_TRAVEL_X 300.0f
#define DEFAULT_TRAVEL_Y 220.0f
#define DEFAULT_HOMING 1           /* $20 $21 $22: switches exist, so home first */
#define DEFAULT_BAUD 115200UL

#endif
