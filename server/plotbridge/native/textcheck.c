/* textcheck: is an upload text? (server/plotbridge/importing/detect.py, check_text)
 *
 * Finds the first control byte a text file does not hold: below 32 except tab, LF,
 * FF, CR and ^Z (26). Eight bytes at a time: only a word holding a byte below 32 (a
 * newline, mostly) is looked at byte by byte.
 */

#include <stdint.h>
#include <string.h>

/* bit c set: byte c (below 32) is allowed */
#define ALLOWED ((1u << 9) | (1u << 10) | (1u << 12) | (1u << 13) | (1u << 26))
#define ONES 0x0101010101010101ull
#define HIGHS 0x8080808080808080ull

static long in_bytes(const unsigned char *data, long from, long to)
{
    for (long k = from; k < to; k++)
        if (data[k] < 32 && !(ALLOWED >> data[k] & 1))
            return k;
    return -1;
}

/* The offset of the first such byte in data[0, len), or -1 when there is none. */
long first_control(const unsigned char *data, long len)
{
    long k = 0;
    for (; k + 8 <= len; k += 8) {
        uint64_t w;
        memcpy(&w, data + k, 8);
        /* a byte below 32 sets its high bit here (the classic "has less than" test) */
        if ((w - 32 * ONES) & ~w & HIGHS) {
            long at = in_bytes(data, k, k + 8);
            if (at >= 0)
                return at;
        }
    }
    return in_bytes(data, k, len);
}
