/* Step interrupt (Timer1): integer Bresenham over the segment ring. */
#ifndef STEPPER_H
#define STEPPER_H
#include <stdint.h>
#include "config.h"

void stepper_init(void);
void stepper_apply_settings(void);  /* invert masks, pulse length */
void stepper_start(void);           /* run the queued segments (no-op if running or empty) */
uint8_t stepper_halt(void);         /* stop at once (any context); 1 if it was moving */
uint8_t stepper_busy(void);         /* nonzero while the steppers run */
void stepper_enable(uint8_t on);
uint8_t stepper_enabled(void);
void stepper_get_position(int32_t *motor);
void stepper_set_position(const int32_t *motor);
/* One step pulse on the motors in mask toward dir_negative (homing; not while running). */
void stepper_pulse(uint8_t mask, uint8_t dir_negative);
#endif
