#include "linebuf.h"

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
    return c > ' ' && c <= 'Z' && c != '(' && c != ';';
}

uint8_t linebuf_feed(linebuf_t *lb, uint8_t c)
{
    if (c == '\n' || c == '\r') {
        if (c == '\n' && (lb->flags & LBF_AFTER_CR)) {
            lb->flags = 0;
            return LB_NONE;
        }
        uint8_t f = lb->flags;
        uint8_t result = f & LBF_OVERFLOW ? LB_OVERFLOW : f & LBF_BAD_BYTE ? LB_BAD_BYTE : LB_LINE;
        lb->text[lb->len] = 0;
        lb->len = 0; /* text stays readable until the next byte */
        lb->flags = c == '\r' ? LBF_AFTER_CR : 0;
        return result;
    }
    uint8_t f = lb->flags & (uint8_t)~LBF_AFTER_CR;
    lb->flags = f;
    if (f & LBF_SEMICOLON)
        return LB_NONE;
    if (f & LBF_PAREN) {
        if (c == ')')
            lb->flags = f & (uint8_t)~LBF_PAREN;
        return LB_NONE;
    }
    if (c == '(') {
        lb->flags = f | LBF_PAREN;
        return LB_NONE;
    }
    if (c == ';') {
        lb->flags = f | LBF_SEMICOLON;
        return LB_NONE;
    }
    if (c == ' ' || c == '\t')
        return LB_NONE;
    if (c < 0x20 || c > 0x7E) { /* control bytes, NUL and binary noise */
        lb->flags = f | LBF_BAD_BYTE;
        return LB_NONE;
    }
    if (c >= 'a' && c <= 'z')
        c = (uint8_t)(c - 'a' + 'A');
    if (lb->len >= LINE_SIZE) {
        lb->flags = f | LBF_OVERFLOW;
        return LB_NONE;
    }
    lb->text[lb->len++] = (char)c;
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
            uint8_t len = lb->len, start = len;
            char *text = lb->text;
            uint8_t c;
            while (len < LINE_SIZE && plain(c = ring[tail & mask])) {
                text[len++] = (char)c;
                if (++tail == head)
                    break;
            }
            if (len != start) {
                lb->len = len;
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
