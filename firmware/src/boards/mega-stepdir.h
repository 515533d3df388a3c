/* XY plotter: Arduino Mega 2560 with step/dir drivers, min and max end
 * switches on both axes, a panic button, a status LED, 160 steps/mm. */
#ifndef BOARD_H
#define BOARD_H

#define BOARD_NAME "mega-stepdir"
#define DRIVE_KIND DRIVE_STEPDIR

#define X_ENABLE E, 3   /* D5 */
#define X_STEP H, 3     /* D6 */
#define X_DIR H, 4      /* D7 */
#define Y_ENABLE B, 5   /* D11 */
#define Y_STEP B, 6     /* D12 */
#define Y_DIR B, 7      /* D13 */

#define X_MIN D, 3      /* D18 */
#define X_MAX D, 2      /* D19 */
#define Y_MIN D, 1      /* D20 */
#define Y_MAX D, 0      /* D21 */
#define BUTTON_ESTOP E, 4  /* D2: panic */
#define LED_STOP F, 3      /* A3: status LED, lit in an emergency stop */

#define SERVO F, 1      /* A1 (edges set by the timer interrupt) */

#define BENCH_ISR F, 5  /* A5 */

#define DEFAULT_STEPS_PER_MM 160.0f
#define DEFAULT_MAX_RATE 6000.0f   /* mm/min: 16 kHz */
#define DEFAULT_ACCEL 1000.0f      /* mm/s^2 */
#define DEFAULT_TRAVEL_X 300.0f
#define DEFAULT_TRAVEL_Y 220.0f
#define DEFAULT_HOMING 1           /* $20 $21 $22 */
#define DEFAULT_BAUD 115200UL

#endif
