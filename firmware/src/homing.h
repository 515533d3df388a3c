/* $H: find the switches at the axis minimum (or maximum, per $23), set
 * machine zero at the trip point, and back off by the pull-off distance. */
#ifndef HOMING_H
#define HOMING_H
#include <stdint.h>
uint8_t homing_run(void); /* 0, or the alarm code of the failure */
#endif
