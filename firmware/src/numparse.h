/* Decimal number reader shared by the G-code and $ parsers. Pure. */
#ifndef NUMPARSE_H
#define NUMPARSE_H
#include <stdint.h>

/* Reads [+-]digits[.digits] at line[*pos]; advances *pos. Returns 1 on
 * success. Any number of digits is accepted; magnitudes above 1e9 are refused
 * (no machine quantity comes near), so 40-digit numbers are an error, not
 * an overflow. */
uint8_t read_number(const char *line, uint8_t *pos, float *out);
#endif
