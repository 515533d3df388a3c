/* Assembles received bytes into command lines: strips spaces, ( ) and ;
 * comments, upper-cases, and reports overflow instead of writing past the
 * buffer. Pure. */
#ifndef LINEBUF_H
#define LINEBUF_H
#include <stdint.h>
#include "config.h"

enum { LB_NONE, LB_LINE, LB_OVERFLOW, LB_BAD_BYTE };

/* linebuf_t.flags: the state between bytes, in one byte (RAM on the 328P) */
#define LBF_PAREN 0x01     /* inside ( ) */
#define LBF_SEMICOLON 0x02 /* after ; up to the line end */
#define LBF_AFTER_CR 0x04  /* the \n of a \r\n pair ends no second line */
#define LBF_OVERFLOW 0x08  /* more than LINE_MAX kept characters */
#define LBF_BAD_BYTE 0x10  /* a control byte or binary noise */

typedef struct {
    /* LINE_MAX characters and the NUL; a whole EEPROM line where startup
     * lines are loaded into it (GRBL_LINES) */
    char text[(GRBL_LINES ? LINE_SIZE : LINE_MAX) + 1];
    uint8_t len;
    uint8_t flags;
} linebuf_t;

void linebuf_reset(linebuf_t *lb);
/* Feed one byte; LB_LINE / LB_OVERFLOW / LB_BAD_BYTE at a line end: text is
 * then NUL-terminated (a blank line gives LB_LINE with len 0) and stays valid
 * until the next byte is fed. */
uint8_t linebuf_feed(linebuf_t *lb, uint8_t c);
/* Feed the bytes of a ring (ring[index & mask]) from *tail up to head, or
 * up to and including a line end; *tail is advanced past the bytes taken.
 * Returns linebuf_feed's result for the last byte (LB_NONE: no line end
 * yet). A line's common run of letters, digits, signs and points is copied
 * in one loop with the length in a register. */
uint8_t linebuf_feed_ring(linebuf_t *lb, const uint8_t *ring, uint8_t mask, uint8_t *tail,
                          uint8_t head);
#endif
