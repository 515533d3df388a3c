/* `peek ADDR LEN` on the control socket: bytes of the simulated data memory as
 * hex, so tests can read firmware state (e.g. the planner ring, located with
 * the ELF's symbol table) while it runs. */
#ifndef PEEK_H
#define PEEK_H
#include <stdio.h>
#include "sim_avr.h"

/* arg: "ADDR LEN" (decimal or 0x hex; ELF data addresses 0x800000+ accepted). */
void peek_reply(avr_t *avr, const char *arg, FILE *reply);
#endif
