/* Everything the firmware prints. Only acknowledgements contain "ok" or
 * "error"; every unsolicited message avoids both words. */
#ifndef REPORT_H
#define REPORT_H
#include <stdint.h>
#include <avr/pgmspace.h>
#include "serial.h"

void report_pstr(PGM_P s);
void report_str(const char *s);
void report_uint(uint32_t v);
void report_fixed(float v, uint8_t decimals);
void report_xyz(const float *v);       /* "x,y,z" in mm or inches ($13) */
void report_status_code(uint8_t code); /* "ok" or "error:N" */
void report_alarm(uint8_t code);
void report_banner(void);
void report_unlock_hint(void);
void report_msg(PGM_P text);           /* [MSG:text] */
#define RPT(s) report_pstr(PSTR(s))
/* one character: cheaper than RPT of a one-character string (no string, one register) */
static inline void report_char(char c) { serial_write((uint8_t)c); }
#endif
