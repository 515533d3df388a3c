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
enum { W_X, W_Y, W_Z, W_I, W_J, W_R, W_F, W_P, W_S, W_N, W_T, W_L, W_COUNT };
/* words whose value is kept (L's only for G10: without GRBL_WCS it is
 * always an unused word, its value never read) */
#define W_VALUES (GRBL_WCS ? W_COUNT : W_L)
/* each letter's word plus one (0: none), by letter - 'A': one flash read a
 * word instead of a search, and no table in RAM */
#define WORD(letter, w) [(letter) - 'A'] = (w) + 1
static const uint8_t word_of_letter[26] PROGMEM = {
    WORD('X', W_X), WORD('Y', W_Y), WORD('Z', W_Z), WORD('I', W_I), WORD('J', W_J), WORD('R', W_R),
    WORD('F', W_F), WORD('P', W_P), WORD('S', W_S), WORD('N', W_N), WORD('T', W_T), WORD('L', W_L),
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
       GRP_PEN = 32, GRP_STOP = 64, GRP_G53 = 128 /* (not a group: G53 seen) */ };
#define PEN_M300 3 /* blk->pen while parsing: M300, whose S decides */

/* 1 when the group (0: none) was already named on the line; marks it */
static inline uint8_t seen_group(uint8_t *groups, uint8_t group)
{
    uint8_t was = *groups & group;
    *groups |= group;
    return was;
}

/* non-modal G commands (GRBL's group 0, one per line) */
enum { NM_NONE, NM_DWELL, NM_G28, NM_G92, NM_G92_1, NM_G10, NM_SET_HOME };
#define N_COORD_SYSTEMS 6 /* G54..G59 */

/* An unknown G/M number: a fraction on G0-G9 is "needs an integer" (23),
 * anything else unsupported (20). */
static uint8_t bad_code(uint16_t code10)
{
    return code10 % 10 && code10 < 100 ? ERR_NOT_INTEGER : ERR_UNSUPPORTED;
}

void gc_init(gc_state_t *st)
{
    memset(st, 0, sizeof(*st));
    st->motion = MOTION_G0;
    st->z = 1.0f;
#if GRBL_WCS
    coord_load(0, st->wcs);
#endif
}

void gc_program_end(gc_state_t *st)
{
    st->motion = MOTION_G1;
    st->incremental = 0;
    st->plane = 0;
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

float gc_wco(const gc_state_t *st, uint8_t a)
{
#if GRBL_WCS
    return st->wcs[a] + st->g92[a];
#else
    return st->g92[a];
#endif
}

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
        if (letter == 'G' || letter == 'M') {
            if (undo->motion == UNDO_NONE)
                memcpy(undo, st, sizeof(*st));
            if (v < 0.0f || v > 1000.0f)
                return ERR_UNSUPPORTED;
            uint16_t code10 = (uint16_t)lroundf(v * 10.0f);
            if (fabsf(v * 10.0f - (float)code10) > 0.001f)
                return ERR_NOT_INTEGER;
            if (letter == 'G') {
                if (jog && code10 != 200 && code10 != 210 && code10 != 900 && code10 != 910 &&
                    code10 != 530)
                    return ERR_INVALID_JOG;
                switch (code10) {
                case 0: case 10: case 20: case 30: case 800:
                    if (motion >= 0)
                        return ERR_MODAL_CONFLICT;
                    motion = code10 == 800 ? MOTION_NONE : (int8_t)(code10 / 10);
                    break;
#if GRBL_WCS
                case 100: case 281: case 301:
#endif
                case 40: case 280: case 300: case 920: case 921:
                    if (non_modal)
                        return ERR_MODAL_CONFLICT;
                    if (code10 >= 300 && code10 < 400)
                        home_slot = GC_SLOT_G30;
                    non_modal = code10 == 40 ? NM_DWELL : code10 == 100 ? NM_G10 :
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
                case 530: groups |= GRP_G53; break;
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
                default: return bad_code(code10);
                }
            } else {
                if (jog)
                    return ERR_INVALID_JOG;
                uint8_t m_group = 0; /* (M17/M18/M84 and coolant: none) */
                switch (code10) {
                case 30: case 40: blk->pen = PEN_DOWN; m_group = GRP_PEN; break;
                case 50: blk->pen = PEN_UP; m_group = GRP_PEN; break;
                case 3000: blk->pen = PEN_M300; m_group = GRP_PEN; break;
                case 170: blk->motors = MOTORS_ON; break;
                case 180: case 840: blk->motors = MOTORS_OFF; break;
                case 0: case 10: blk->pause = 1; m_group = GRP_STOP; break;
                case 20: case 300: blk->program_end = 1; m_group = GRP_STOP; break;
                case 80: case 90: break; /* coolant: no coolant on a plotter */
                default: return bad_code(code10);
                }
                if (seen_group(&groups, m_group))
                    return ERR_MODAL_CONFLICT;
            }
            continue;
        }
        if (w >= W_COUNT)
            return jog ? ERR_INVALID_JOG : ERR_UNSUPPORTED;
        if (seen & WB(w))
            return ERR_WORD_REPEATED;
        /* words whose value must not be negative (GRBL's rule) */
        if (w >= W_F && v < 0.0f) /* (the float compare only for those words) */
            return ERR_NEGATIVE;
        seen |= (uint16_t)WB(w);
    }

    uint8_t g53 = groups & GRP_G53;
    uint8_t inverse = 0;
#if GRBL_G93
    inverse = st->inverse_time; /* F is 1/min then, not a length */
#endif
    if (st->inches) /* lengths (X Y Z I J R F) to mm once; mm lines multiply nothing */
        for (uint8_t w = W_X; w <= (inverse ? W_R : W_F); w++)
            if (seen & WB(w))
                val[w] *= 25.4f;
    uint8_t axes = (uint8_t)(seen & (WB(W_X) | WB(W_Y)));
    if (jog) {
        if (seen & ~(WB(W_X) | WB(W_Y) | WB(W_F) | WB(W_N)))
            return ERR_INVALID_JOG;
        if (!axes || !(seen & WB(W_F)))
            return ERR_INVALID_JOG;
        motion = MOTION_G1;
    }
    if ((seen & WB(W_N)) && val[W_N] > MAX_LINE_NUMBER)
        return ERR_LINE_NUMBER;
    if (seen & WB(W_N)) /* GRBL keeps the whole part */
        blk->line = (uint32_t)val[W_N];
    if ((seen & WB(W_T)) && val[W_T] > 255.0f)
        return ERR_TOOL_NUMBER;
    if (seen & WB(W_F)) {
        if (jog)
            blk->feed = val[W_F];
        else
            st->feed = val[W_F];
    }
    if (blk->pen == PEN_M300) {
        if (!(seen & WB(W_S)))
            return ERR_VALUE_WORD_MISSING;
        blk->pen = val[W_S] <= M300_THRESHOLD ? PEN_DOWN : PEN_UP;
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
        if (non_modal == NM_G92) {
            st->g92[2] = 0.0f;
            st->g92[2] = st->z - gc_wco(st, 2) - val[W_Z];
        } else if (non_modal == NM_NONE && !g53) {
            if ((motion >= 0 ? motion : st->motion) == MOTION_NONE)
                return ERR_AXIS_WORDS_UNUSED;
            float z = st->incremental ? st->z + val[W_Z] : val[W_Z] + gc_wco(st, 2);
            if (magnitude_above(z, GC_MAX_COORD))
                return ERR_INVALID_TARGET;
            st->z = z;
            if (blk->pen == PEN_KEEP) /* an explicit M3/M5 on the same line wins */
                blk->pen = z <= Z_PEN_THRESHOLD ? PEN_DOWN : PEN_UP;
        }
    }
    if (g53 && non_modal)
        return ERR_MODAL_CONFLICT; /* both in GRBL's non-modal group */
    if (g53 && !jog && (motion >= 0 ? motion : st->motion) > MOTION_G1)
        return ERR_G53_MOTION;

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

    uint16_t used = (uint16_t)(WB(W_X) | WB(W_Y) | WB(W_Z) | WB(W_F) | WB(W_N) | WB(W_S) | WB(W_T));

    if (non_modal == NM_DWELL) {
        if (axes || motion >= 0)
            return ERR_AXIS_COMMAND_CONFLICT;
        if (!(seen & (1u << W_P)))
            return ERR_VALUE_WORD_MISSING;
        if (val[W_P] < 0.0f)
            return ERR_NEGATIVE;
        if (val[W_P] > 3600.0f)
            return ERR_BAD_NUMBER;
        blk->action = ACT_DWELL;
        blk->dwell_s = val[W_P];
        used |= 1u << W_P;
    } else if (non_modal == NM_G92) {
        if (motion >= 0)
            return ERR_AXIS_COMMAND_CONFLICT;
        if (!axes)
            return ERR_NO_AXIS_WORDS;
        for (uint8_t a = 0; a < N_AXIS; a++)
            if (axes & (1u << a)) {
                st->g92[a] = 0.0f;
                st->g92[a] = st->pos[a] - gc_wco(st, a) - val[a];
            }
        blk->wco_changed = 1;
    } else if (non_modal == NM_G92_1) {
        if (motion >= 0)
            return ERR_AXIS_COMMAND_CONFLICT;
        memset(st->g92, 0, sizeof(st->g92));
        blk->wco_changed = 1;
#if GRBL_WCS
    } else if (non_modal == NM_G10) {
        if (motion >= 0)
            return ERR_AXIS_COMMAND_CONFLICT;
        if (!(seen & (WB(W_X) | WB(W_Y) | WB(W_Z))))
            return ERR_NO_AXIS_WORDS;
        if ((~seen & (WB(W_P) | WB(W_L))))
            return ERR_VALUE_WORD_MISSING;
        if (val[W_P] >= N_COORD_SYSTEMS + 1)
            return ERR_UNSUPPORTED_COORD;
        uint8_t l = (uint8_t)val[W_L], p = (uint8_t)val[W_P];
        if ((l != 2 && l != 20) || (l == 2 && (seen & WB(W_R))))
            return ERR_UNSUPPORTED;
        uint8_t slot = p ? (uint8_t)(p - 1) : st->coord;
        if (!coord_load(slot, blk->store))
            return ERR_EEPROM_READ;
        for (uint8_t a = 0; a < GC_AXES; a++) {
            if (!(seen & WB(a)))
                continue;
            /* L20: the offset that makes the machine's position read val;
             * L2: the offset itself */
            float machine = a < N_AXIS ? st->pos[a] : st->z;
            blk->store[a] = l == 20 ? machine - st->g92[a] - val[a] : val[a];
        }
        if (slot == st->coord) {
            memcpy(st->wcs, blk->store, sizeof(st->wcs));
            blk->wco_changed = 1;
        }
        blk->store_slot = (uint8_t)(slot + 1);
        used |= WB(W_P) | WB(W_L);
#endif
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
        if (moving && st->motion == MOTION_NONE)
            return ERR_AXIS_WORDS_UNUSED;
        if (!moving && (motion == MOTION_G2 || motion == MOTION_G3))
            return seen & WB(W_Z) ? ERR_ARC_NO_PLANE_AXIS : ERR_NO_AXIS_WORDS;
        if (moving || motion == MOTION_G2 || motion == MOTION_G3) {
            if (st->motion != MOTION_G0) {
                float f = jog ? blk->feed : st->feed;
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
                    used |= (1u << W_I) | (1u << W_J);
                }
            }
            memcpy(st->pos, target, sizeof(st->pos));
        }
    }
    if (seen & ~used)
        return ERR_UNUSED_WORDS;
    if (blk->program_end)
        gc_program_end(st);
#if GRBL_G93
    if (inverse) /* an inverse-time F holds for its own line only */
        st->feed = 0.0f;
#endif
    return STATUS_OK;
}
