/* Limit switches and buttons of the board header (boards/NAME.h), all to
 * ground with pull-ups. */
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
uint8_t inputs_limits(void);        /* PIN_X_LIMIT | PIN_Y_LIMIT: any switch of the axis closed */
uint8_t inputs_home_switches(void); /* the same for the switch at the homing end ($23) only */
void inputs_poll(void);             /* boards without pin-change wiring: from the 1 ms timer */
void inputs_homing(uint8_t on);     /* while homing, switches do not raise alarms */
void inputs_led(uint8_t on);
#endif
