/* Limit switches (PB1, PB2) and buttons (PC0 stop, PC1 pause, PC2 resume),
 * all to ground with pull-ups; pin-change interrupts act on them at once. */
#ifndef INPUTS_H
#define INPUTS_H
#include <stdint.h>

#define PIN_X_LIMIT 0x01
#define PIN_Y_LIMIT 0x02
#define PIN_ESTOP 0x04
#define PIN_PAUSE 0x08
#define PIN_RESUME 0x10

void inputs_init(void);
uint8_t inputs_read(void);          /* PIN_* bits of active inputs */
uint8_t inputs_limits(void);        /* PIN_X_LIMIT | PIN_Y_LIMIT as active */
void inputs_homing(uint8_t on);     /* while homing, switches do not raise alarms */
void inputs_led(uint8_t on);
#endif
