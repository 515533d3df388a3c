/* Pen servo on PB3 = OC2A: 500-2500 us pulses about every 20 ms. */
#ifndef SERVO_H
#define SERVO_H
#include <stdint.h>

void servo_init(void);
void servo_set_us(uint16_t us);               /* at once */
void servo_move(uint16_t us, uint16_t ms);     /* slewed: there in about `ms` (0: at once); us 500-2500 */
uint16_t servo_get_us(void);
/* Milliseconds since start, counted by the same timer (wraps after 49 days). */
uint32_t timebase_ms(void);
#endif
