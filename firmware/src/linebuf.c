#include "linebuf.h"

void linebuf_reset(linebuf_t *lb)
{
    lb->len = 0;
    lb->in_paren = lb->in_semicolon = lb->overflow = lb->bad_byte = lb->after_cr = 0;
    lb->text[0] = 0;
}

uint8_t linebuf_feed_rest(linebuf_t *lb, uint8_t c)
{
    if (c == '\n' || c == '\r') {
        if (c == '\n' && lb->after_cr) {
            lb->after_cr = 0;
            return LB_NONE;
        }
        uint8_t result = lb->overflow ? LB_OVERFLOW : lb->bad_byte ? LB_BAD_BYTE : LB_LINE;
        lb->text[lb->len] = 0;
        lb->len = 0; /* text stays readable until the next byte */
        lb->in_paren = lb->in_semicolon = lb->overflow = lb->bad_byte = 0;
        lb->after_cr = c == '\r';
        return result;
    }
    lb->after_cr = 0;
    if (lb->in_semicolon)
        return LB_NONE;
    if (lb->in_paren) {
        if (c == ')')
            lb->in_paren = 0;
        return LB_NONE;
    }
    if (c == '(') {
        lb->in_paren = 1;
        return LB_NONE;
    }
    if (c == ';') {
        lb->in_semicolon = 1;
        return LB_NONE;
    }
    if (c == ' ' || c == '\t')
        return LB_NONE;
    if (c < 0x20 || c > 0x7E) { /* control bytes, NUL and binary noise */
        lb->bad_byte = 1;
        return LB_NONE;
    }
    if (c >= 'a' && c <= 'z')
        c = (uint8_t)(c - 'a' + 'A');
    if (lb->len >= LINE_SIZE) {
        lb->overflow = 1;
        return LB_NONE;
    }
    lb->text[lb->len++] = (char)c;
    return LB_NONE;
}
