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
static inline uint8_t linebuf_feed(linebuf_t *lb, uint8_t c);
/* linebuf_feed for every byte but the common one below */
uint8_t linebuf_feed_rest(linebuf_t *lb, uint8_t c);

static inline uint8_t linebuf_feed(linebuf_t *lb, uint8_t c)
{
    /* the common byte inline, in one test of each: an upper-case letter,
     * digit or sign outside a comment, with room left (the line is
     * NUL-terminated at its end, not after every byte) */
    if (c > ' ' && c <= 'Z' && c != '(' && c != ';' && !(lb->in_paren | lb->in_semicolon) &&
        lb->len < LINE_SIZE) {
        lb->after_cr = 0;
        lb->text[lb->len++] = (char)c;
        return LB_NONE;
    }
    return linebuf_feed_rest(lb, c);
}
#endif
