/* What simavr 1.6 gets wrong on a reset of the running chip (a watchdog
 * reset, which a firmware may use for its soft reset): it clears the PINx
 * registers although the pins' levels (pull-ups, closed switches) have not
 * changed, and it turns INT0/INT1 level polling back on (see main.c). Each
 * module's reset is wrapped to put that right. */
#ifndef RESET_FIX_H
#define RESET_FIX_H

#include "sim_avr.h"

void reset_fix_install(avr_t *avr);

#endif
