/* Machine settings ($N), their defaults (docs/INTERNALS.md) and the checksum
 * that guards their EEPROM copy. Pure: no register access. */
#ifndef SETTINGS_H
#define SETTINGS_H
#include <stdint.h>
#include "config.h"

#define SETTINGS_VERSION 4

typedef struct {
    float steps_per_mm[N_AXIS];   /* $100 $101 */
    float max_rate[N_AXIS];       /* $110 $111 mm/min */
    float accel[N_AXIS];          /* $120 $121 mm/s^2 */
    float max_travel[N_AXIS];     /* $130 $131 mm */
    float junction_deviation;     /* $11 mm */
    float arc_tolerance;          /* $12 mm */
    float homing_feed;            /* $24 mm/min */
    float homing_seek;            /* $25 mm/min */
    float homing_pulloff;         /* $27 mm */
    uint16_t homing_debounce_ms;  /* $26 */
    uint16_t pen_up_us;           /* $60 */
    uint16_t pen_down_us;         /* $61 */
    uint16_t pen_settle_ms;       /* $62 */
    uint16_t pen_lower_ms;        /* $64: time the servo takes to lower the pen (0: at once) */
    uint16_t pen_raise_ms;        /* $65: time to raise it */
    uint8_t pulse_us;             /* $0 */
    uint8_t idle_delay_ms;        /* $1 (255: keep enabled) */
    uint8_t step_invert;          /* $2 */
    uint8_t dir_invert;           /* $3 */
    uint8_t enable_invert;        /* $4 */
    uint8_t limit_invert;         /* $5 */
    uint8_t report_mask;          /* $10 */
    uint8_t report_inches;        /* $13 */
    uint8_t soft_limits;          /* $20 */
    uint8_t hard_limits;          /* $21 */
    uint8_t homing_enable;        /* $22 */
    uint8_t homing_dir_mask;      /* $23 */
    uint8_t corexy;               /* $63 */
} settings_t;

extern settings_t settings;

/* How many $ rows $$ lists; settings_id(i) is the i-th one's number. */
extern const uint8_t settings_count;
uint8_t settings_id(uint8_t i);

void settings_defaults(settings_t *s);
/* Store value under $id; returns STATUS_OK or an error code. */
uint8_t settings_set(settings_t *s, uint8_t id, float value);
/* Read $id into *value; 0 when the id is unknown. */
uint8_t settings_get(const settings_t *s, uint8_t id, float *value);
/* 1 if $id holds a whole number (printed without decimals). */
uint8_t settings_is_integer(uint8_t id);
uint8_t settings_checksum(const uint8_t *data, uint16_t len);

/* EEPROM side (settings_store.c, AVR only): 1 if the stored copy was valid
 * (a bad one restores everything to defaults, as GRBL does). */
uint8_t settings_load(void);
void settings_save(void);
/* $RST=$ settings, $RST=# stored positions, $RST=* everything (bits). */
#define RESTORE_SETTINGS 1
#define RESTORE_COORDS 2
#define RESTORE_LINES 4
#define RESTORE_ALL 7
void settings_restore(uint8_t what);
/* $N0, $N1 (slots 0, 1) and the $I= string (EELINE_BUILD_INFO), GRBL_LINES:
 * line holds LINE_SIZE + 1 chars; 0 (and an empty line) when the copy was bad. */
#define EELINE_STARTUP_COUNT 2
#define EELINE_BUILD_INFO 2
#define EELINE_COUNT 3
uint8_t eeline_load(uint8_t slot, char *line);
void eeline_save(uint8_t slot, const char *line);
#endif
