/* Assembles received bytes into command lines: strips spaces, ( ) and ;
 * comments, upper-cases, and reports overflow instead of writing past the
 * buffer. Pure. */
#ifndef LINEBUF_H
#define LINEBUF_H
#include <stdint.h>
#include "config.h"

enum { LB_NONE, LB_LINE, LB_OVERFLOW, LB_BAD_BYTE };

typedef struct {
    char text[LINE_SIZE + 1];
    uint8_t len;
    uint8_t in_paren, in_semicolon, overflow, bad_byte;
    uint8_t after_cr; /* the \n of a \r\n pair ends no second line */
} linebuf_t;

void linebuf_reset(linebuf_t *lb);
/* Feed one byte; LB_LINE / LB_OVERFLOW / LB_BAD_BYTE at a line end: text is
 * then NUL-terminated (a blank line gives LB_LINE with len 0) and stays valid
 * until the next byte is fed. */
uint8_t linebuf_feed(linebuf_t *lb, uint8_t c);
#endif
