/* Number reading, line assembly, formatting, ring indices. */
#include <math.h>
#include <string.h>
#include "check.h"
#include "fmt.h"
#include "linebuf.h"
#include "numparse.h"
#include "ring.h"
#include "tests.h"

static float num(const char *s, uint8_t *ok, uint8_t *end)
{
    float v = -999.0f;
    uint8_t pos = 0;
    *ok = read_number(s, &pos, &v);
    *end = pos;
    return v;
}

void test_numbers(void)
{
    uint8_t ok, end;
    CHECK_NEAR(num("12.5", &ok, &end), 12.5, 1e-6);
    CHECK(ok && end == 4);
    CHECK_NEAR(num("-0.001X", &ok, &end), -0.001, 1e-9);
    CHECK(ok && end == 6);
    CHECK_NEAR(num("+7", &ok, &end), 7, 0);
    CHECK_NEAR(num(".5", &ok, &end), 0.5, 0);
    CHECK_NEAR(num("5.", &ok, &end), 5, 0);
    CHECK_NEAR(num("300.000", &ok, &end), 300, 0);
    CHECK_NEAR(num("123.456", &ok, &end), 123.456, 1e-4);
    /* across the digit sum's step from 16 to 32 bits (at 6553) */
    CHECK_NEAR(num("6552.9", &ok, &end), 6552.9, 1e-3);
    CHECK_NEAR(num("6553.9", &ok, &end), 6553.9, 1e-3);
    CHECK_NEAR(num("65535", &ok, &end), 65535, 0);
    CHECK_NEAR(num("65536.5", &ok, &end), 65536.5, 0);
    CHECK_NEAR(num("0065539", &ok, &end), 65539, 0);
    CHECK(ok && end == 7);
    /* 40 digits after the point: fine, rounds */
    CHECK_NEAR(num("1.234567890123456789012345678901234567890", &ok, &end), 1.2345679, 1e-6);
    CHECK(ok && end == strlen("1.234567890123456789012345678901234567890"));
    CHECK_NEAR(num("0.0000000000000000000000000000000000000000001", &ok, &end), 0, 1e-30);
    CHECK(ok);
    /* 40 integer digits: refused, not an overflow */
    num("1234567890123456789012345678901234567890", &ok, &end);
    CHECK(!ok);
    num("10000000001", &ok, &end);
    CHECK(!ok);
    CHECK_NEAR(num("999999999", &ok, &end), 999999999.0, 100);
    num("-", &ok, &end);
    CHECK(!ok);
    num(".", &ok, &end);
    CHECK(!ok);
    num("X", &ok, &end);
    CHECK(!ok);
    CHECK_NEAR(num("1.2.3", &ok, &end), 1.2, 1e-6);
    CHECK(end == 3);
}

static uint8_t feed_all(linebuf_t *lb, const char *s, uint8_t *last)
{
    uint8_t lines = 0;
    for (; *s; s++) {
        uint8_t r = linebuf_feed(lb, (uint8_t)*s);
        if (r != LB_NONE) {
            lines++;
            *last = r;
        }
    }
    return lines;
}

void test_linebuf(void)
{
    linebuf_t lb;
    uint8_t last = 0;
    linebuf_reset(&lb);
    CHECK(feed_all(&lb, "g1 x10 (a comment) y2 ; rest\n", &last) == 1);
    CHECK(last == LB_LINE && strcmp(lb.text, "G1X10Y2") == 0);
    /* \r\n ends one line, not two; a blank line still ends a line */
    CHECK(feed_all(&lb, "G0X1\r\n", &last) == 1 && strcmp(lb.text, "G0X1") == 0);
    CHECK(feed_all(&lb, "\n", &last) == 1 && last == LB_LINE && lb.text[0] == 0);
    CHECK(feed_all(&lb, "\r\r", &last) == 2);
    /* overflow is reported at the line end, and the next line is clean */
    char longline[300];
    memset(longline, 'X', sizeof(longline));
    longline[299] = 0;
    CHECK(feed_all(&lb, longline, &last) == 0);
    CHECK(lb.len == LINE_MAX);
    CHECK(feed_all(&lb, "\n", &last) == 1 && last == LB_OVERFLOW);
    /* GRBL's 80-byte buffer: 79 characters are a line, 80 overflow */
    longline[LINE_MAX] = 0;
    CHECK(feed_all(&lb, longline, &last) == 0 && feed_all(&lb, "\n", &last) == 1 && last == LB_LINE);
    longline[LINE_MAX] = 'X';
    longline[LINE_MAX + 1] = 0;
    CHECK(feed_all(&lb, longline, &last) == 0 && feed_all(&lb, "\n", &last) == 1 && last == LB_OVERFLOW);
    CHECK(feed_all(&lb, "G1\n", &last) == 1 && last == LB_LINE && strcmp(lb.text, "G1") == 0);
    /* NUL and binary bytes */
    uint8_t bin[] = {'G', 0, 0xFF, '1', '\n'};
    uint8_t r = LB_NONE;
    for (unsigned i = 0; i < sizeof(bin); i++)
        r = linebuf_feed(&lb, bin[i]);
    CHECK(r == LB_BAD_BYTE);
    /* comment spanning the whole line, unterminated paren */
    CHECK(feed_all(&lb, "(only a comment)\n", &last) == 1 && lb.text[0] == 0);
    CHECK(feed_all(&lb, "G1 (open\nG2\n", &last) == 2 && strcmp(lb.text, "G2") == 0);
}

/* linebuf_feed_ring gives the lines, results and texts that linebuf_feed
 * gives byte by byte, for bytes arriving in any pieces across the ring's wrap */
void test_linebuf_ring(void)
{
    static const char stream[] =
        "X112.5Y67.25\nx1 y2 (c) ;rest\r\nG1\r\rN5G1X-.5\n(open\nXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXX"
        "XXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXXX\nG\x01" "1\n\n$$\n";
    const uint8_t n = (uint8_t)(sizeof(stream) - 1);
    for (uint8_t piece = 1; piece <= 17; piece += 4) {
        for (uint8_t start = 0; start < 16; start += 5) {
            uint8_t ring[16];
            linebuf_t a, b;
            linebuf_reset(&a);
            linebuf_reset(&b);
            uint8_t head = start, tail = start, fed = 0, lines_a = 0, lines_b = 0;
            for (uint8_t i = 0; i < n; i++) {
                uint8_t r = linebuf_feed(&a, (uint8_t)stream[i]);
                if (r != LB_NONE)
                    lines_a++;
            }
            while (fed < n || tail != head) {
                /* the sender adds up to `piece` bytes while the ring has room */
                for (uint8_t k = 0; k < piece && fed < n && (uint8_t)(head - tail) < 16; k++)
                    ring[head++ & 15] = (uint8_t)stream[fed++];
                uint8_t before = tail;
                uint8_t r = linebuf_feed_ring(&b, ring, 15, &tail, head);
                CHECK(tail != before || before == head);
                if (r != LB_NONE) {
                    lines_b++;
                    /* the same line came out of the byte-by-byte feed */
                    linebuf_t c;
                    linebuf_reset(&c);
                    uint8_t rc = LB_NONE, seen = 0;
                    for (uint8_t i = 0; i < n && seen < lines_b; i++) {
                        rc = linebuf_feed(&c, (uint8_t)stream[i]);
                        seen += rc != LB_NONE;
                    }
                    CHECK(rc == r && strcmp(c.text, b.text) == 0);
                }
            }
            CHECK(lines_a == 10 && lines_b == lines_a);
        }
    }
}

void test_fmt(void)
{
    char b[FMT_MAX];
    fmt_fixed(b, 12.0f, 3);
    CHECK(strcmp(b, "12.000") == 0);
    fmt_fixed(b, 3.5f, 3);
    CHECK(strcmp(b, "3.500") == 0);
    fmt_fixed(b, -0.0125f, 3);
    CHECK(strcmp(b, "-0.013") == 0 || strcmp(b, "-0.012") == 0);
    fmt_fixed(b, -0.0001f, 3);
    CHECK(strcmp(b, "0.000") == 0);
    fmt_fixed(b, 299.9995f, 3);
    CHECK(strcmp(b, "300.000") == 0 || strcmp(b, "299.999") == 0 || strcmp(b, "300.000") == 0);
    fmt_fixed(b, 1.0e30f, 3);
    CHECK(strlen(b) < FMT_MAX);
    fmt_fixed(b, 6000.0f, 0);
    CHECK(strcmp(b, "6000") == 0);
    fmt_uint(b, 4294967295u);
    CHECK(strcmp(b, "4294967295") == 0);
    fmt_int(b, -2147483647 - 1);
    CHECK(strcmp(b, "-2147483648") == 0);
    fmt_int(b, 0);
    CHECK(strcmp(b, "0") == 0);
}

void test_ring(void)
{
    /* free-running indices: a 128-byte ring really holds 128 bytes, across the 255 wrap */
    uint8_t head = 250, tail = 250;
    CHECK(ring_free(head, tail, 128) == 128);
    head = (uint8_t)(head + 128);
    CHECK(ring_count(head, tail) == 128 && ring_free(head, tail, 128) == 0);
    tail = (uint8_t)(tail + 100);
    CHECK(ring_count(head, tail) == 28);
    CHECK(ring_slot(255, 128) == 127 && ring_slot(0, 128) == 0 && ring_slot(130, 128) == 2);
}
