/* Machine state and the execution of parsed blocks: motion into the
 * planner, pen moves, dwells, alarms, feed hold, and the polling that every
 * wait loop runs so that realtime requests act everywhere. */
#ifndef MACHINE_H
#define MACHINE_H
#include <stdint.h>
#include "gcode.h"

#define RESET_NOW 1       /* 0x18: the line being executed gets no acknowledgement */
#define RESET_AFTER_ACK 2 /* leaving check mode */
#define ALARM_LOCKED 0xFF /* power-up with homing enabled: locked, no ALARM:N printed */

typedef struct {
    uint8_t alarm;         /* 0 or the alarm code holding the machine */
    uint8_t check;         /* $C dry run */
    uint8_t homing;
    uint8_t abort;         /* unwind the line being executed */
    uint8_t reset;         /* soft reset requested: RESET_NOW or RESET_AFTER_ACK */
    uint8_t hold;          /* feed hold active */
    uint8_t jog;           /* the queued motion is a jog */
    uint8_t jog_cancel;
    uint8_t pen_down;
    uint8_t dwelling;
    uint8_t homed;
    uint8_t sleep;         /* $SLP: 1 after its ok, 2 asleep until a reset */
    uint8_t pen_lifted;    /* a hold lifted the pen (pen_down stays set) */
    uint8_t resuming;      /* pen lowered again after a hold: waiting out the settle */
    uint8_t wco_countdown; /* status reports until WCO is shown again (0: next one) */
    uint8_t ov_countdown;  /* the same for Ov */
    uint32_t resume_at;    /* machine_ms() when motion may go on */
} machine_t;

extern machine_t mach;
extern gc_state_t gc;

void machine_init(void);
void machine_poll(void);              /* realtime work; call from every wait loop */
uint8_t machine_moving(void);         /* motion queued or running */
/* sleep until an interrupt, unless realtime work or output waits */
void machine_idle_wait(void);
uint8_t machine_sync(void);           /* wait for all motion to end; 0 if aborted */
uint8_t machine_execute(const gc_block_t *blk);
uint8_t machine_jog(const char *body);
/* Soft limits: 1 (and ALARM:2 after the queued motion ends) if blk leaves the work area. */
uint8_t machine_check_limits(const gc_block_t *blk);
void machine_pen(uint8_t down);
void machine_pen_up_now(void);        /* alarm, reset: the servo lifts at once, no wait */
uint8_t machine_dwell_ms(uint32_t ms);
void machine_resync(void);            /* planner and parser take the stepper position */
void machine_report_status(void);
void machine_alarm(uint8_t code);     /* main-context alarm (soft limit, homing) */
uint32_t machine_ms(void);
#endif
