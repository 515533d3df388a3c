#include "linebuf.h"
#include "ring.h"

void linebuf_reset(linebuf_t *lb)
{
    lb->len = 0;
    lb->flags = 0;
    lb->text[0] = 0;
}

/* a byte kept as it is outside a comment: upper-case letters, digits,
 * signs, points and the rest of printable ASCII up to 'Z' */
static inline uint8_t plain(uint8_t c)
{
    return (uint8_t)(c - '!') <= 'Z' - '!' && c != '(' && c != ';'; /* (one compare for the range) */
}

uint8_t linebuf_feed(linebuf_t *lb, uint8_t c)
{
    uint8_t f = lb->flags;
    if (c == '\n' || c == '\r') {
        if (c == '\n' && (f & LBF_AFTER_CR)) {
            lb->flags = 0;
            return LB_NONE;
        }
        uint8_t result = f & LBF_OVERFLOW ? LB_OVERFLOW : f & LBF_BAD_BYTE ? LB_BAD_BYTE : LB_LINE;
        lb->text[lb->len] = 0;
        lb->len = 0; /* text stays readable until the next byte */
        lb->flags = c == '\r' ? LBF_AFTER_CR : 0;
        return result;
    }
    f &= (uint8_t)~LBF_AFTER_CR;
    if (f & LBF_SEMICOLON) {
        /* the rest of the line is a comment */
    } else if (f & LBF_PAREN) {
        if (c == ')')
            f &= (uint8_t)~LBF_PAREN;
    } else if (c == '(') {
        f |= LBF_PAREN;
    } else if (c == ';') {
        f |= LBF_SEMICOLON;
    } else if (c == ' ' || c == '\t') {
        /* spaces are dropped */
    } else if (c < 0x20 || c > 0x7E) { /* control bytes, NUL and binary noise */
        f |= LBF_BAD_BYTE;
    } else if (lb->len >= LINE_MAX) {
        f |= LBF_OVERFLOW;
    } else {
        if (c >= 'a' && c <= 'z')
            c = (uint8_t)(c - 'a' + 'A');
        lb->text[lb->len++] = (char)c;
    }
    lb->flags = f;
    return LB_NONE;
}

uint8_t linebuf_feed_ring(linebuf_t *lb, const uint8_t *ring, uint8_t mask, uint8_t *tail_io,
                          uint8_t head)
{
    uint8_t tail = *tail_io, r = LB_NONE;
    while (tail != head) {
        if (!(lb->flags & (LBF_PAREN | LBF_SEMICOLON))) {
            /* the common run: no comment state to keep, no line end in it
             * (the line is NUL-terminated at its end, not after every byte) */
            uint8_t len = lb->len;
            /* at most the bytes in the ring and the room in the line: one
             * count down a byte (an overflow is linebuf_feed's) */
            uint8_t n = ring_count(head, tail), room = (uint8_t)(LINE_MAX - len);
            if (n > room)
                n = room;
            char *t = lb->text + len;
            for (; n; n--) {
                uint8_t c = ring[tail & mask];
                if (!plain(c))
                    break;
                *t++ = (char)c;
                tail++;
            }
            uint8_t end = (uint8_t)(t - lb->text);
            if (end != len) {
                lb->len = end;
                lb->flags &= (uint8_t)~LBF_AFTER_CR;
                if (tail == head)
                    break;
            }
        }
        r = linebuf_feed(lb, ring[tail++ & mask]);
        if (r != LB_NONE)
            break;
    }
    *tail_io = tail;
    return r;
}
