#include <math.h>
#include <stddef.h>
#include <string.h>
#include "float_bits.h"
#include "gcode.h"
#include "numparse.h"
#include "progmem.h"
#include "status.h"

#define ARC_RADIUS_ABS_TOL 0.005f
#define ARC_RADIUS_REL_TOL 0.001f
#define Z_PEN_THRESHOLD 0.0f
#define M300_THRESHOLD 40.0f /* M300 S30 down, S50 up */

/* word letters that carry a value, as bits for repeat detection */
enum { W_X, W_Y, W_Z, W_I, W_J, W_R, W_F, W_P, W_S, W_N, W_T, W_L, W_K, W_COUNT };
/* words whose value is kept in val[]: T is checked as it is read (as GRBL
 * does), L kept as G10's small integer (GRBL truncates it), K never read (no
 * Z arcs: GRBL ignores it in G17) */
#define W_VALUES W_T
/* each letter's word plus one (0: none), by letter - 'A': one flash read a
 * word instead of a search, and no table in RAM */
#define WORD(letter, w) [(letter) - 'A'] = (w) + 1
static const uint8_t word_of_letter[26] PROGMEM = {
    WORD('X', W_X), WORD('Y', W_Y), WORD('Z', W_Z), WORD('I', W_I), WORD('J', W_J), WORD('R', W_R),
    WORD('F', W_F), WORD('P', W_P), WORD('S', W_S), WORD('N', W_N), WORD('T', W_T), WORD('L', W_L),
    WORD('K', W_K),
};
#define WB(w) (1u << (w))
#define MAX_LINE_NUMBER 10000000.0f /* GRBL's limit on N (exact in a float) */

/* A float's bits: on the AVR every float compare or add is a library call
 * (50-100 cycles), and the tests below on every axis word of every line are
 * exact on the bits. */
/* |v| > limit for a finite v and a positive limit: the magnitudes' bit
 * patterns order as their values do */
static uint8_t magnitude_above(float v, float limit)
{
    return (float_bits(v) & 0x7FFFFFFFu) > float_bits(limit);
}

/* modal groups a line may name once, as bits */
enum { GRP_UNITS = 1, GRP_DIST = 2, GRP_PLANE = 4, GRP_COORD = 8, GRP_FEED_MODE = 16,
       GRP_PEN = 32, GRP_STOP = 64, GRP_COOLANT = 128 };
#define PEN_M300 3 /* blk->pen while parsing: M300, whose S decides */

/* 1 when the group (0: none) was already named on the line; marks it */
static inline uint8_t seen_group(uint8_t *groups, uint8_t group)
{
    uint8_t was = *groups & group;
    *groups |= group;
    return was;
}

/* non-modal G commands (GRBL's group 0, one per line); from NM_G28 on they
 * are GRBL's axis commands (a G0-G3 on their line is error:24) */
enum { NM_NONE, NM_DWELL, NM_SET_HOME, NM_G92_1, NM_G53, NM_G28, NM_G92, NM_G10 };
#define N_COORD_SYSTEMS 6 /* G54..G59 */

/* GRBL's whole G numbers whose fractions (other than the ones it knows)
 * are "needs an integer" (23): 0-4 10 17-21 40 49 53-59 80 93 94, as bits.
 * A fraction on any other G (28.2, 38.1, 43.2, 61.1, 90.1, 92.2) or an
 * unknown number is unsupported (20); a fraction on any M is 23. */
static const uint8_t g_whole[12] PROGMEM = {0x1F, 0x04, 0x3E, 0x00, 0x00, 0x01, 0xE2,
                                            0x0F, 0x00, 0x00, 0x01, 0x60};

static uint8_t bad_code(char letter, uint16_t code10)
{
    uint8_t n = (uint8_t)(code10 / 10);
    if (!(code10 % 10))
        return ERR_UNSUPPORTED;
    if (letter == 'M' || (code10 < 960 && pgm_read_byte(&g_whole[n >> 3]) & (1u << (n & 7))))
        return ERR_NOT_INTEGER;
    return ERR_UNSUPPORTED;
}

void gc_init(gc_state_t *st)
{
    memset(st, 0, sizeof(*st));
    st->motion = MOTION_G0;
    coord_load(0, st->wcs);
}

void gc_program_end(gc_state_t *st)
{
    st->motion = MOTION_G1;
    st->incremental = 0;
    st->plane = 0;
    st->coolant = 0;
#if GRBL_G93
    st->inverse_time = 0;
#endif
#if GRBL_WCS
    /* GRBL: back to G54 (its offset comes from EEPROM again) */
    if (st->coord) {
        st->coord = 0;
        coord_load(0, st->wcs);
    }
#endif
}

float gc_wco(const gc_state_t *st, uint8_t a) { return st->wcs[a] + st->g92[a]; }

/* Centre of an R-form arc: on the perpendicular bisector of the chord;
 * negative R picks the long way round. */
static uint8_t arc_center_from_radius(const float *s, const float *t, float r, uint8_t cw, float *c)
{
    float dx = t[0] - s[0], dy = t[1] - s[1];
    float d2 = dx * dx + dy * dy;
    if (d2 == 0.0f)
        return ERR_INVALID_TARGET;
    float h2 = 4.0f * r * r - d2;
    if (h2 < 0.0f) {
        if (h2 < -ARC_RADIUS_ABS_TOL * d2)
            return ERR_ARC_RADIUS;
        h2 = 0.0f;
    }
    float h = -sqrtf(h2) / sqrtf(d2);
    if (!cw)
        h = -h;
    if (r < 0.0f)
        h = -h;
    c[0] = s[0] + 0.5f * (dx - dy * h);
    c[1] = s[1] + 0.5f * (dy + dx * h);
    return STATUS_OK;
}

#define UNDO_NONE 0xFF /* undo->motion while the whole state is not in it */

void gc_undo(gc_state_t *st, const gc_state_t *undo, const gc_block_t *blk)
{
    if (undo->motion != UNDO_NONE) {
        memcpy(st, undo, sizeof(*st));
    } else {
        st->feed = undo->feed;
        st->z = undo->z;
        memcpy(st->pos, blk->start, sizeof(st->pos));
    }
}

uint8_t gc_parse(const char *line, gc_state_t *st, gc_block_t *blk, uint8_t jog, gc_state_t *undo)
{
    float val[W_VALUES];
    uint16_t seen = 0;
    int8_t motion = -1;
    uint8_t non_modal = NM_NONE;
    uint8_t home_slot = GC_SLOT_G28; /* G28 or G30, and their .1 */
    uint8_t groups = 0; /* GRP_*: modal groups seen on this line (one byte of the frame) */

    memset(blk, 0, offsetof(gc_block_t, feed));
    /* what gc_undo puts back: a line without G or M words changes only
     * feed, z and pos (pos as it was is blk->start); the whole state is
     * copied before the first G or M word changes any of it */
    undo->motion = UNDO_NONE;
    undo->feed = st->feed;
    undo->z = st->z;
    memcpy(blk->start, st->pos, sizeof(blk->start));
    if (jog) { /* (st is the jog's copy) GRBL's jog: a G1 at units per minute */
        st->motion = MOTION_G1;
#if GRBL_G93
        st->inverse_time = 0;
#endif
    }
    for (uint8_t i = 0; line[i];) {
        char letter = line[i++];
        if (letter == '/') /* block delete: GRBL ignores the character */
            continue;
        if (letter < 'A' || letter > 'Z')
            return ERR_EXPECTED_LETTER;
        /* the number read straight into its word's slot (G, M and the
         * unsupported letters: into blk->dwell_s, which only a dwell writes,
         * after this loop): no float of its own in the frame */
        uint8_t w = (uint8_t)(pgm_read_byte(&word_of_letter[letter - 'A']) - 1); /* letter: A..Z here */
        float *vp = w < W_VALUES ? &val[w] : &blk->dwell_s;
        if (!read_number(line, &i, vp))
            return ERR_BAD_NUMBER;
        float v = *vp;
        if (w == W_L)
            blk->l_word = (uint8_t)v;
        if (w == W_T && (int32_t)float_bits(v) > (int32_t)float_bits(255.0f)) /* (a negative T: 4 below) */
            return ERR_TOOL_NUMBER;
        if (letter == 'G' || letter == 'M') {
            if (undo->motion == UNDO_NONE)
                memcpy(undo, st, sizeof(*st));
            float v10 = v * 10.0f;
            float r10 = v10 + 0.5f;
            /* above 1000, or negative (its sign bit) but for -0 (G-0 is G0
             * to GRBL, whose whole part and fraction of -0 are 0) */
            if (float_bits(r10) > float_bits(10000.5f))
                return ERR_UNSUPPORTED;
            uint16_t code10 = (uint16_t)r10;
            if (fabsf(v10 - (float)code10) > 0.001f)
                return ERR_NOT_INTEGER;
            /* a command a jog may not have is refused after every other
             * check (error:16), as GRBL orders them */
            if (jog && (letter == 'M' || (code10 != 200 && code10 != 210 && code10 != 900 &&
                                          code10 != 910 && code10 != 530)))
                blk->jog_bad = 1;
            if (letter == 'G') {
                switch (code10) {
                case 0: case 10: case 20: case 30: case 800:
                    /* GRBL: a second axis command is error:24 before the group's 21 */
                    if (code10 != 800 && ((uint8_t)motion <= MOTION_G3 || non_modal >= NM_G28))
                        return ERR_AXIS_COMMAND_CONFLICT;
                    if (motion >= 0)
                        return ERR_MODAL_CONFLICT;
                    motion = code10 == 800 ? MOTION_NONE : (int8_t)(code10 / 10);
                    break;
#if GRBL_WCS
                case 281: case 301:
#endif
                case 40: case 100: case 280: case 300: case 530: case 920: case 921:
                    if (!(code10 % 10) && code10 != 40 && code10 != 530 && (uint8_t)motion <= MOTION_G3)
                        return ERR_AXIS_COMMAND_CONFLICT;
                    if (non_modal)
                        return ERR_MODAL_CONFLICT;
                    if (code10 >= 300 && code10 < 400)
                        home_slot = GC_SLOT_G30;
                    non_modal = code10 == 40 ? NM_DWELL : code10 == 100 ? NM_G10 : code10 == 530 ? NM_G53 :
                                code10 % 10 && code10 < 400 ? NM_SET_HOME :
                                code10 < 400 ? NM_G28 : code10 == 920 ? NM_G92 : NM_G92_1;
                    break;
#if GRBL_WCS
                case 550: case 560: case 570: case 580: case 590:
#endif
                case 540:
                    if (seen_group(&groups, GRP_COORD))
                        return ERR_MODAL_CONFLICT;
#if GRBL_WCS
                    {
                        uint8_t c = (uint8_t)(code10 / 10 - 54);
                        if (c != st->coord) {
                            st->coord = c;
                            blk->wco_changed = 1;
                            if (!coord_load(c, st->wcs))
                                return ERR_EEPROM_READ;
                        }
                    }
#endif
                    break;
#if GRBL_G93
                case 930:
#endif
                case 940:
                    if (seen_group(&groups, GRP_FEED_MODE))
                        return ERR_MODAL_CONFLICT;
#if GRBL_G93
                    if (st->inverse_time && code10 == 940)
                        st->feed = 0.0f; /* G93 to G94: the feed is undefined until an F */
                    st->inverse_time = code10 == 930;
#endif
                    break;
                case 170: case 180: case 190:
                    if (seen_group(&groups, GRP_PLANE))
                        return ERR_MODAL_CONFLICT;
                    st->plane = (uint8_t)(code10 / 10 - 17);
                    break;
                case 200: case 210:
                    if (seen_group(&groups, GRP_UNITS))
                        return ERR_MODAL_CONFLICT;
                    st->inches = code10 == 200;
                    break;
                case 900: case 910:
                    if (seen_group(&groups, GRP_DIST))
                        return ERR_MODAL_CONFLICT;
                    st->incremental = code10 == 910;
                    break;
                /* accepted, nothing to do on a pen plotter: G40 (no cutter
                 * compensation), G49 (no tool length offset), G61 (exact
                 * path), G91.1 (IJK relative) */
                case 400: case 490: case 610: case 911: break;
                default: return bad_code(letter, code10);
                }
            } else {
                uint8_t m_group = 0; /* (M17/M18/M84: none) */
                switch (code10) {
                case 30: case 40: blk->pen = PEN_DOWN; m_group = GRP_PEN; break;
                case 50: blk->pen = PEN_UP; m_group = GRP_PEN; break;
                case 3000: blk->pen = PEN_M300; m_group = GRP_PEN; break;
                case 170: blk->motors = MOTORS_ON; break;
                case 180: case 840: blk->motors = MOTORS_OFF; break;
                case 0: blk->pause = 1; /* fall through */
                case 10: m_group = GRP_STOP; break; /* M1: GRBL 1.1h has no optional stop switch */
                case 20: case 300: blk->program_end = 1; m_group = GRP_STOP; break;
                /* coolant: no output on a plotter, the state only ($G) */
                case 80: case 90: st->coolant = code10 == 80; m_group = GRP_COOLANT; break;
                default: return bad_code(letter, code10);
                }
                if (seen_group(&groups, m_group))
                    return ERR_MODAL_CONFLICT;
            }
            continue;
        }
        if (w >= W_COUNT)
            return ERR_UNSUPPORTED;
        if (seen & WB(w))
            return ERR_WORD_REPEATED;
        /* words whose value must not be negative (GRBL's rule) */
        if (w >= W_F && w <= W_T && v < 0.0f) /* F P S N T (the float compare only for those) */
            return ERR_NEGATIVE;
        seen |= (uint16_t)WB(w);
    }

    uint8_t g53 = non_modal == NM_G53;
    uint8_t inverse = 0;
#if GRBL_G93
    inverse = st->inverse_time; /* F is 1/min then, not a length */
#endif
    if (st->inches) /* lengths (X Y Z I J R F) to mm once; mm lines multiply nothing */
        for (uint8_t w = W_X; w <= (inverse ? W_R : W_F); w++)
            if (seen & WB(w))
                val[w] *= 25.4f;
    uint8_t axes = (uint8_t)(seen & (WB(W_X) | WB(W_Y)));
    if ((seen & WB(W_N)) && magnitude_above(val[W_N], MAX_LINE_NUMBER))
        return ERR_LINE_NUMBER;
    if (seen & WB(W_N)) /* GRBL keeps the whole part */
        blk->line = (uint32_t)val[W_N];
    if (jog && !(seen & WB(W_F))) /* (GRBL: before the other checks) */
        return ERR_UNDEFINED_FEED;
    if (seen & WB(W_F))
        st->feed = val[W_F];
    if (blk->pen == PEN_M300) {
        if (!(seen & WB(W_S)))
            return ERR_VALUE_WORD_MISSING;
        blk->pen = val[W_S] <= M300_THRESHOLD ? PEN_DOWN : PEN_UP;
    }
    /* G92.1 with axis words: they are a motion in the modal mode, its
     * target in the frame before the line, as GRBL computes it; the G92
     * offset is cleared once the line is valid */
    if (non_modal == NM_G92_1) {
        blk->clear_g92 = 1;
        non_modal = NM_NONE;
    }
#if GRBL_WCS
    if (non_modal == NM_SET_HOME) {
        /* G28.1/G30.1 store where the machine is; axis words on the line
         * are then an ordinary motion in the modal mode, as in GRBL */
        memcpy(blk->store, st->pos, sizeof(st->pos));
        blk->store[2] = st->z;
        blk->store_slot = (uint8_t)(home_slot + 1);
        non_modal = NM_NONE;
    }
#endif
    if (seen & WB(W_Z)) {
        /* Z is the pen, decided on machine Z so that no offset can flip it;
         * only a motion moves the pen (G92 Z, G10 Z and G53 Z never do) */
        if (non_modal <= NM_DWELL) {
            float z = st->incremental ? st->z + val[W_Z] : val[W_Z] + gc_wco(st, 2);
            if (magnitude_above(z, GC_MAX_COORD))
                return ERR_INVALID_TARGET;
            st->z = z;
            if (blk->pen == PEN_KEEP) /* an explicit M3/M5 on the same line wins */
                blk->pen = z <= Z_PEN_THRESHOLD ? PEN_DOWN : PEN_UP;
        }
    }
    uint8_t mode = (uint8_t)(motion >= 0 ? motion : st->motion);
    if (g53 && mode > MOTION_G1)
        return ERR_G53_MOTION;
    /* G80: an axis word on the line is error:31, whatever command it is for */
    if (mode == MOTION_NONE && (seen & (WB(W_X) | WB(W_Y) | WB(W_Z))))
        return ERR_AXIS_WORDS_UNUSED;
    /* an explicit G1 without axis words still needs a feed (GRBL) */
    if (motion == MOTION_G1 && (int32_t)float_bits(st->feed) <= 0)
        return ERR_UNDEFINED_FEED;

    /* where the axis words point, in machine mm: made in the block's
     * target itself (no copy; unread by the actions that have none), and
     * where the line starts */
    float *target = blk->target;
    for (uint8_t a = 0; a < N_AXIS; a++) {
        float t = st->pos[a];
        if (axes & (1u << a)) {
            float v = val[a];
            if (g53)
                t = v;
            else if (st->incremental)
                t += v;
            else {
                float off = gc_wco(st, a);
                /* no offset, the usual case: the word itself, no float add
                 * (the add would turn -0 into +0, so -0 takes it) */
                t = float_bits(off) == 0 && float_bits(v) != 0x80000000u ? v : v + off;
            }
            if (magnitude_above(t, GC_MAX_COORD))
                return ERR_INVALID_TARGET;
        }
        target[a] = t;
    }

    /* (a jog leaves S and T unused: error:36, as GRBL) */
    uint16_t used = (uint16_t)(WB(W_X) | WB(W_Y) | WB(W_Z) | WB(W_F) | WB(W_N) | (jog ? 0 : WB(W_S) | WB(W_T)));

    if (non_modal == NM_DWELL) {
        /* a motion on its line (in the modal mode) follows the dwell, as in GRBL */
        if (!(seen & (1u << W_P)))
            return ERR_VALUE_WORD_MISSING;
        if (magnitude_above(val[W_P], 3600.0f)) /* (P is not negative: refused as it was read) */
            return ERR_BAD_NUMBER;
        blk->dwell = 1;
        blk->dwell_s = val[W_P];
        used |= 1u << W_P;
    }
    if (non_modal >= NM_G92) {
        /* G92 and G10 share one path: an offset from each axis word, the
         * one that makes the machine position read it (G92: g92 = machine -
         * wcs - word; G10 L20: wcs = machine - g92 - word; G10 L2: the word) */
        if (!(seen & (WB(W_X) | WB(W_Y) | WB(W_Z))))
            return ERR_NO_AXIS_WORDS;
        float *dst = st->g92;
        const float *other = st->wcs;
        uint8_t l = 20;
        if (non_modal == NM_G10) {
            if ((~seen & (WB(W_P) | WB(W_L))))
                return ERR_VALUE_WORD_MISSING;
            /* P and L as GRBL truncates them (P is not negative: integer
             * compares of its bits) */
            if (float_bits(val[W_P]) >= float_bits(N_COORD_SYSTEMS + 1.0f))
                return ERR_UNSUPPORTED_COORD;
            l = blk->l_word;
            if ((l != 2 && l != 20) || (l == 2 && (seen & WB(W_R))))
                return ERR_UNSUPPORTED;
#if GRBL_WCS
            uint8_t p = (uint8_t)val[W_P];
            uint8_t slot = p ? (uint8_t)(p - 1) : st->coord;
            if (!coord_load(slot, blk->store))
                return ERR_EEPROM_READ;
            dst = slot == st->coord ? st->wcs : blk->store; /* (EEPROM from blk->store) */
#else
            /* G54 only: P0 and P1 (what senders' zero buttons send); its
             * offset is in RAM since power-up */
            if (float_bits(val[W_P]) >= float_bits(2.0f))
                return ERR_UNSUPPORTED;
            const uint8_t slot = 0;
            dst = st->wcs;
#endif
            other = st->g92;
            blk->store_slot = (uint8_t)(slot + 1);
            used |= WB(W_P) | WB(W_L);
        }
        for (uint8_t a = 0; a < GC_AXES; a++) {
            if (!(seen & WB(a)))
                continue;
            float machine = a < N_AXIS ? st->pos[a] : st->z;
            float v = l == 20 ? machine - other[a] - val[a] : val[a];
            dst[a] = v;
            blk->store[a] = v;
        }
#if !GRBL_WCS
        memcpy(blk->store, st->wcs, sizeof(st->wcs)); /* (only G10 writes it to EEPROM) */
#endif
        blk->wco_changed = dst != blk->store; /* (not for another system than the current) */
    } else if (non_modal == NM_G28) {
        if (motion >= 0)
            return ERR_AXIS_COMMAND_CONFLICT;
        blk->action = ACT_G28;
        blk->has_via = axes != 0;
        memcpy(blk->via, target, sizeof(blk->via));
        /* then to the stored position (machine 0 without GRBL_WCS); with
         * axis words only those axes go there, as GRBL 1.1 does. (Read into
         * blk->store, unused without a store_slot: gc_parse's own frame
         * stays within the 64 bytes the AVR reaches in one instruction.) */
        float *home = blk->store;
        memset(home, 0, sizeof(blk->store));
#if GRBL_WCS
        if (!coord_load(home_slot, home))
            return ERR_EEPROM_READ;
#else
        (void)home_slot;
#endif
        uint8_t words = (uint8_t)(seen & (WB(W_X) | WB(W_Y) | WB(W_Z)));
        for (uint8_t a = 0; a < N_AXIS; a++)
            st->pos[a] = blk->target[a] = words && !(words & (1u << a)) ? st->pos[a] : home[a];
    } else {
        if (motion >= 0)
            st->motion = (uint8_t)motion;
        uint8_t moving = axes != 0;
        if (!moving && (motion == MOTION_G2 || motion == MOTION_G3))
            return seen & WB(W_Z) ? ERR_ARC_NO_PLANE_AXIS : ERR_NO_AXIS_WORDS;
        if (moving || motion == MOTION_G2 || motion == MOTION_G3) {
            if (st->motion != MOTION_G0) {
                float f = st->feed;
                if ((int32_t)float_bits(f) <= 0) /* f <= 0 (never negative: +0 or -0) */
                    return ERR_UNDEFINED_FEED;
                blk->feed = f;
            }
            blk->action = st->motion == MOTION_G0 ? ACT_RAPID : st->motion == MOTION_G1 ? ACT_LINE : ACT_ARC;
            blk->inverse_time = inverse;
            if (blk->action == ACT_ARC) {
                if (st->plane)
                    return ERR_UNSUPPORTED; /* an arc through Z: the pen has no Z motor */
                blk->clockwise = st->motion == MOTION_G2;
                if (seen & (1u << W_R)) {
                    if (seen & ((1u << W_I) | (1u << W_J)))
                        return ERR_UNUSED_WORDS;
                    if (fabsf(val[W_R]) > GC_MAX_COORD) /* the long way round a huge circle */
                        return ERR_INVALID_TARGET;
                    uint8_t e = arc_center_from_radius(st->pos, target, val[W_R],
                                                       blk->clockwise, blk->center);
                    if (e)
                        return e;
                    used |= 1u << W_R;
                } else {
                    if (!(seen & ((1u << W_I) | (1u << W_J))))
                        return ERR_NO_OFFSETS;
                    float r0 = 0.0f;
                    for (uint8_t a = 0; a < N_AXIS; a++) {
                        float off = (seen & (1u << (W_I + a))) ? val[W_I + a] : 0.0f;
                        if (fabsf(off) > GC_MAX_COORD)
                            return ERR_INVALID_TARGET;
                        blk->center[a] = st->pos[a] + off;
                        r0 += off * off;
                    }
                    r0 = sqrtf(r0);
                    float ex = target[0] - blk->center[0], ey = target[1] - blk->center[1];
                    float r1 = sqrtf(ex * ex + ey * ey);
                    float dr = fabsf(r1 - r0);
                    if (r0 == 0.0f || (dr > ARC_RADIUS_ABS_TOL && dr > ARC_RADIUS_REL_TOL * r0))
                        return ERR_INVALID_TARGET;
                    used |= (1u << W_I) | (1u << W_J) | (1u << W_K);
                }
            }
            memcpy(st->pos, target, sizeof(st->pos));
        }
    }
    if (seen & ~used)
        return ERR_UNUSED_WORDS;
    /* GRBL's last jog check; a jog without axis words is refused too
     * (GRBL 1.1h would jog to machine 0) */
    if (jog && (blk->jog_bad || !(seen & (WB(W_X) | WB(W_Y) | WB(W_Z)))))
        return ERR_INVALID_JOG;
    if (blk->clear_g92) {
        memset(st->g92, 0, sizeof(st->g92));
        blk->wco_changed = 1;
    }
    if (seen & WB(W_S))
        st->spindle = val[W_S];
    if (blk->program_end)
        gc_program_end(st);
#if GRBL_G93
    if (inverse) /* an inverse-time F holds for its own line only */
        st->feed = 0.0f;
#endif
    return STATUS_OK;
}
