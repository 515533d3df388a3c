/* One board's wiring from its firmware header; the Makefile compiles this
 * file once per board with BOARD_HEADER and BOARD_VAR set. */
#include "board_pins.h"

#define DRIVE_STEPDIR SIM_STEPDIR
#define DRIVE_UNIPOLAR SIM_UNIPOLAR
#define DRIVE_BIPOLAR SIM_BIPOLAR
#include BOARD_HEADER

enum { P_A = 'A', P_B = 'B', P_C = 'C', P_D = 'D', P_E = 'E', P_F = 'F', P_G = 'G', P_H = 'H',
       P_J = 'J', P_K = 'K', P_L = 'L' };
#define SIMPIN_(p, b) { P_##p, b }
#define SIMPIN(...) SIMPIN_(__VA_ARGS__)
#define NONE { 0, 0 }

#ifdef X_STEP
#define STEPDIR_PINS .step = { SIMPIN(X_STEP), SIMPIN(Y_STEP) }, .dir = { SIMPIN(X_DIR), SIMPIN(Y_DIR) },
#ifdef Y_ENABLE
#define ENABLE_PINS .enable = { SIMPIN(X_ENABLE), SIMPIN(Y_ENABLE) },
#else
#define ENABLE_PINS .enable = { SIMPIN(X_ENABLE), NONE },
#endif
#else
#define STEPDIR_PINS
#define ENABLE_PINS
#endif
#ifdef X_COIL_A
#define COIL_PINS .coil = { { SIMPIN(X_COIL_A), SIMPIN(X_COIL_B), SIMPIN(X_COIL_C), SIMPIN(X_COIL_D) }, \
			    { SIMPIN(Y_COIL_A), SIMPIN(Y_COIL_B), SIMPIN(Y_COIL_C), SIMPIN(Y_COIL_D) } },
#else
#define COIL_PINS
#endif
#ifdef X_LIMIT
#define LIMIT_PINS .limit = { SIMPIN(X_LIMIT), SIMPIN(Y_LIMIT) },
#else
#define LIMIT_PINS
#endif
#ifdef X_MIN
#define END_PINS .min = { SIMPIN(X_MIN), SIMPIN(Y_MIN) }, .max = { SIMPIN(X_MAX), SIMPIN(Y_MAX) },
#else
#define END_PINS
#endif
#ifdef BUTTON_ESTOP
#define B_ESTOP SIMPIN(BUTTON_ESTOP)
#else
#define B_ESTOP NONE
#endif
#ifdef BUTTON_PAUSE
#define B_PAUSE SIMPIN(BUTTON_PAUSE)
#else
#define B_PAUSE NONE
#endif
#ifdef BUTTON_RESUME
#define B_RESUME SIMPIN(BUTTON_RESUME)
#else
#define B_RESUME NONE
#endif
#ifdef LED_STOP
#define LED_PIN SIMPIN(LED_STOP)
#else
#define LED_PIN NONE
#endif
#if DRIVE_KIND == DRIVE_BIPOLAR && BIPOLAR_FULL_STEP
#define STRIDE 2
#else
#define STRIDE 1
#endif

const struct board_pins BOARD_VAR = {
	.name = BOARD_NAME,
	.mcu = BOARD_MCU,
	.drive = DRIVE_KIND,
	.coil_stride = STRIDE,
	STEPDIR_PINS ENABLE_PINS COIL_PINS LIMIT_PINS END_PINS
	.button = { B_ESTOP, B_PAUSE, B_RESUME },
	.led = LED_PIN,
	.servo = SIMPIN(SERVO),
	.steps_per_mm = DEFAULT_STEPS_PER_MM,
	.width = DEFAULT_TRAVEL_X,
	.height = DEFAULT_TRAVEL_Y,
	.baud = DEFAULT_BAUD,
};
