/* G-code line parser: turns one stripped, upper-cased line into a checked
 * block of actions, updating the modal state only when the whole line is
 * valid. Pure: motion is executed elsewhere. */
#ifndef GCODE_H
#define GCODE_H
#include <stdint.h>
#include "config.h"

enum { MOTION_G0, MOTION_G1, MOTION_G2, MOTION_G3, MOTION_NONE }; /* NONE: G80 */
enum { ACT_NONE, ACT_RAPID, ACT_LINE, ACT_ARC, ACT_DWELL, ACT_G28 };
enum { PEN_KEEP, PEN_UP, PEN_DOWN };
enum { MOTORS_KEEP, MOTORS_ON, MOTORS_OFF };

#define GC_MAX_COORD 100000.0f /* mm: anything further is a typo, and would overflow step counts */

typedef struct {
    uint8_t motion;       /* MOTION_* */
    uint8_t incremental;  /* G91 */
    uint8_t inches;       /* G20 */
    uint8_t plane;        /* 0 G17, 1 G18, 2 G19 (arcs only in G17: no Z motor) */
    float feed;           /* mm/min; 0 until an F word is seen */
    float pos[N_AXIS];    /* machine mm where the last accepted move ends */
    float offset[N_AXIS]; /* G92: machine = work + offset */
    float z;              /* machine Z of the last Z word: the pen threshold is on it */
    float z_offset;       /* G92 on Z: machine Z = work Z + z_offset (never moves the pen) */
} gc_state_t;

typedef struct {
    uint8_t action;       /* ACT_* */
    uint8_t clockwise;    /* arcs */
    uint8_t pen;          /* PEN_*: applied before the motion */
    uint8_t motors;       /* MOTORS_* */
    uint8_t program_end;  /* M2/M30: after the motion */
    uint8_t pause;        /* M0/M1: feed hold (Hold:0) once the motion before it ends */
    uint8_t wco_changed;  /* G92/G92.1: the status report shows WCO next time */
    uint8_t has_via;      /* G28 with axis words */
    float start[N_AXIS];  /* machine mm */
    float target[N_AXIS];
    float via[N_AXIS];
    float center[N_AXIS];
    float feed;           /* mm/min */
    float dwell_s;
} gc_block_t;

void gc_init(gc_state_t *st);
/* Parse line into *blk against *st. STATUS_OK commits the new modal state;
 * any error leaves *st untouched. jog: parse a $J= body (GRBL's jog rules). */
uint8_t gc_parse(const char *line, gc_state_t *st, gc_block_t *blk, uint8_t jog);
/* Program end (M2/M30): modal state back to the power-up defaults, position kept. */
void gc_program_end(gc_state_t *st);
#endif
