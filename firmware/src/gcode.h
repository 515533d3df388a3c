/* G-code line parser: turns one stripped, upper-cased line into a checked
 * block of actions, updating the modal state only when the whole line is
 * valid. Pure: motion is executed elsewhere. */
#ifndef GCODE_H
#define GCODE_H
#include <stdint.h>
#include "config.h"

enum { MOTION_G0, MOTION_G1, MOTION_G2, MOTION_G3, MOTION_NONE }; /* NONE: G80 */
enum { ACT_NONE, ACT_RAPID, ACT_LINE, ACT_ARC, ACT_G28 }; /* ACT_G28: G28 and G30 */
enum { PEN_KEEP, PEN_UP, PEN_DOWN };
enum { MOTORS_KEEP, MOTORS_ON, MOTORS_OFF };

#define GC_MAX_COORD 100000.0f /* mm: anything further is a typo, and would overflow step counts */
#define GC_AXES 3              /* X, Y and Z (the pen) in offsets and stored positions */
/* stored positions (EEPROM, GRBL_WCS): G54..G59 are 0..5 */
#define GC_SLOT_G28 6
#define GC_SLOT_G30 7
#define GC_SLOTS 8

typedef struct {
    uint8_t motion;       /* MOTION_* */
    uint8_t incremental;  /* G91 */
    uint8_t inches;       /* G20 */
    uint8_t plane;        /* 0 G17, 1 G18, 2 G19 (arcs only in G17: no Z motor) */
#if GRBL_G93
    uint8_t inverse_time; /* G93: F is 1/min per move, and only for its own line */
#endif
    uint8_t coolant;      /* M8 (1) / M9 (0): no output, $G shows it */
#if GRBL_WCS
    uint8_t coord;        /* 0..5: G54..G59 */
#endif
    float wcs[GC_AXES];   /* the selected work system's offset, read from EEPROM (G54 only
                           * without GRBL_WCS) */
    float feed;           /* mm/min; 0 until an F word is seen */
    float spindle;        /* the last S word ($G shows it; the pen ignores it) */
    float pos[N_AXIS];    /* machine mm where the last accepted move ends */
    float z;              /* machine Z of the last Z word (0 at power-up, as GRBL's MPos Z;
                           * the pen stays up until a Z word): the pen threshold is on it */
    float g92[GC_AXES];   /* G92: machine = work + wcs + g92 (never moves the pen) */
} gc_state_t;

typedef struct {
    uint8_t action;       /* ACT_* */
    uint8_t clockwise;    /* arcs */
    uint8_t pen;          /* PEN_*: applied before the motion */
    uint8_t motors;       /* MOTORS_* */
    uint8_t program_end;  /* M2/M30: after the motion */
    uint8_t dwell;        /* G4: dwell_s before the action (a motion on its line) */
    uint8_t pause;        /* M0/M1: feed hold (Hold:0) once the motion before it ends */
    uint8_t wco_changed;  /* G92/G92.1/G10/G54..: the status report shows WCO next time */
    uint8_t has_via;      /* G28 with axis words */
    uint8_t store_slot;   /* G10, G28.1, G30.1: GC_SLOT_* + 1 to write `store` to, 0 none */
    uint8_t inverse_time; /* G93: feed is 1/min, machine scales it by the move's length */
    uint8_t l_word;       /* parse scratch (in the block, not gc_parse's frame): G10's L, */
    uint8_t jog_bad;      /* a G or M word a jog may not have, */
    uint8_t clear_g92;    /* G92.1 (its axis words are a motion) */
    uint32_t line;        /* N word (its whole part), 0 without one */
    /* gc_parse zeroes the fields above and fills these where its action
     * reads them (a 48-byte clear a line saved): feed for a line, an arc
     * or a jog, dwell_s for a dwell (while parsing, the G and M numbers'
     * scratch), start always, target for every motion
     * and G28 (and most other lines), via for G28, center for arcs, store
     * when store_slot is set (G28 reads its stored position into it) */
    float feed;           /* mm/min */
    float dwell_s;
    float store[GC_AXES]; /* machine mm (G28.1/G30.1) or offset (G10) to store */
    float start[N_AXIS];  /* machine mm */
    float target[N_AXIS];
    float via[N_AXIS];
    float center[N_AXIS];
} gc_block_t;

void gc_init(gc_state_t *st);
/* Parse line into *blk against the modal state *st, which it changes in
 * place to the state after the line; on an error, or when the caller
 * refuses the block, the caller puts the state back with gc_undo (undo: the
 * caller's, for this line). No copy of the state a line (~220 cycles) but
 * for a line with G or M words. jog: parse a $J= body (GRBL's jog rules). */
uint8_t gc_parse(const char *line, gc_state_t *st, gc_block_t *blk, uint8_t jog, gc_state_t *undo);
void gc_undo(gc_state_t *st, const gc_state_t *undo, const gc_block_t *blk);
/* Program end (M2/M30): modal state back to the power-up defaults, position kept. */
void gc_program_end(gc_state_t *st);
/* Work coordinate offset (wcs + g92) of axis a (0..2), as WCO and $# show it. */
float gc_wco(const gc_state_t *st, uint8_t a);

/* Stored positions (settings_store.c on the chip, a RAM copy in host
 * builds): 0 and zeros when the copy is bad (GRBL's error:7). */
uint8_t coord_load(uint8_t slot, float *xyz);
void coord_save(uint8_t slot, const float *xyz);
#endif
