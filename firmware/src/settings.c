#include <stddef.h>
#include <string.h>
#include "settings.h"
#include "progmem.h"
#include "status.h"

settings_t settings;

/* The defaults as one image in flash: a copy is smaller than code that
 * stores each field. */
static const settings_t defaults PROGMEM = {
    .steps_per_mm = {DEFAULT_STEPS_PER_MM, DEFAULT_STEPS_PER_MM},
    .max_rate = {DEFAULT_MAX_RATE, DEFAULT_MAX_RATE},
    .accel = {DEFAULT_ACCEL, DEFAULT_ACCEL},
    .max_travel = {DEFAULT_TRAVEL_X, DEFAULT_TRAVEL_Y},
    .junction_deviation = 0.02f,
    .arc_tolerance = 0.002f,
    .homing_feed = 300.0f,
    .homing_seek = 3000.0f,
    .homing_pulloff = 1.0f,
    .homing_debounce_ms = 25,
    .pen_up_us = 1000,
    .pen_down_us = 2000,
    .pen_settle_ms = 150,
    .pulse_us = 4,
    .idle_delay_ms = 255,
    .report_mask = 3,
    .soft_limits = DEFAULT_HOMING, /* the board header: switches or not */
    .hard_limits = DEFAULT_HOMING,
    .homing_enable = DEFAULT_HOMING,
    .homing_dir_mask = 3,
};

/* One row per $ number, in the order $$ lists them: where it lives, its
 * kind, and its limit. FIXED rows are what senders list but a pen plotter
 * has no use for ($6 probe invert, $30/$31 spindle range, $32 laser mode,
 * the Z axis $102 $112 $122 $132: Z is the pen servo): `limit` is the only
 * value they accept. */
enum { K_FLOAT, K_U8, K_U16, K_FIXED };
typedef struct {
    uint8_t id;
    uint8_t offset; /* into settings_t */
    uint8_t kind;
    uint16_t limit; /* K_U8/K_U16: largest value; K_FLOAT: largest (0: 1e6); K_FIXED: the value */
} row_t;

#define F(id, field, max) {id, offsetof(settings_t, field), K_FLOAT, max}
#define B(id, field, max) {id, offsetof(settings_t, field), K_U8, max}
#define W(id, field, max) {id, offsetof(settings_t, field), K_U16, max}
#define X(id, value) {id, 0, K_FIXED, value}
static const row_t rows[] PROGMEM = {
    B(0, pulse_us, 12), /* the pulse must fit well inside a 40 kHz period */
    B(1, idle_delay_ms, 255), B(2, step_invert, 3), B(3, dir_invert, 3), B(4, enable_invert, 1),
    B(5, limit_invert, 3), X(6, 0), B(10, report_mask, 3), F(11, junction_deviation, 0),
    F(12, arc_tolerance, 0), B(13, report_inches, 1), B(20, soft_limits, 1), B(21, hard_limits, 1),
    B(22, homing_enable, 1), B(23, homing_dir_mask, 3), F(24, homing_feed, 0), F(25, homing_seek, 0),
    W(26, homing_debounce_ms, 10000), F(27, homing_pulloff, 0), X(30, 1000), X(31, 0), X(32, 0),
    W(60, pen_up_us, 2500), W(61, pen_down_us, 2500), W(62, pen_settle_ms, 10000), B(63, corexy, 1),
    W(64, pen_lower_ms, 10000), W(65, pen_raise_ms, 10000),
    F(100, steps_per_mm[0], 2000), F(101, steps_per_mm[1], 2000), X(102, 100),
    F(110, max_rate[0], 0), F(111, max_rate[1], 0), X(112, 1000),
    F(120, accel[0], 0), F(121, accel[1], 0), X(122, 100),
    F(130, max_travel[0], 0), F(131, max_travel[1], 0), X(132, 10),
};
const uint8_t settings_count = sizeof(rows) / sizeof(rows[0]);

uint8_t settings_id(uint8_t i) { return pgm_read_byte(&rows[i].id); }

static const row_t *find(uint8_t id)
{
    for (uint8_t i = 0; i < settings_count; i++)
        if (pgm_read_byte(&rows[i].id) == id)
            return &rows[i];
    return 0;
}

void settings_defaults(settings_t *s) { memcpy_P(s, &defaults, sizeof(*s)); }

uint8_t settings_is_integer(uint8_t id)
{
    const row_t *r = find(id);
    return r && pgm_read_byte(&r->kind) != K_FLOAT && id < 100;
}

uint8_t settings_set(settings_t *s, uint8_t id, float value)
{
    const row_t *r = find(id);
    if (value != value)
        return ERR_BAD_NUMBER;
    if (value < 0.0f)
        return ERR_NEGATIVE;
    if (!r)
        return ERR_INVALID_DOLLAR;
    uint8_t kind = pgm_read_byte(&r->kind);
    float limit = (float)pgm_read_word(&r->limit);
    uint8_t *field = (uint8_t *)s + pgm_read_byte(&r->offset);
    if (kind == K_FIXED)
        return value > limit - 0.001f && value < limit + 0.001f ? STATUS_OK : ERR_INVALID_DOLLAR;
    if (kind != K_FLOAT) /* GRBL truncates an integer setting ($1=1.5 is $1=1) */
        value = (float)(uint32_t)value;
    if (id == 20 && value != 0.0f && !s->homing_enable)
        return ERR_SOFT_LIMIT_NO_HOME;
    if (kind == K_FLOAT) {
        /* zero or absurd values would divide by zero or overflow step counts */
        if (value > (limit > 0.0f ? limit : 1.0e6f) || (value == 0.0f && id != 27))
            return ERR_INVALID_DOLLAR;
        memcpy(field, &value, sizeof(value));
        return STATUS_OK;
    }
    if (id == 0 && value < 3.0f)
        return ERR_STEP_PULSE;
    if (value > limit || ((id == 60 || id == 61) && value < 500.0f))
        return ERR_INVALID_DOLLAR;
    uint16_t v = (uint16_t)value;
    if (kind == K_U8)
        *field = (uint8_t)v;
    else
        memcpy(field, &v, sizeof(v));
    return STATUS_OK;
}

uint8_t settings_get(const settings_t *s, uint8_t id, float *value)
{
    const row_t *r = find(id);
    if (!r)
        return 0;
    const uint8_t *field = (const uint8_t *)s + pgm_read_byte(&r->offset);
    uint16_t w;
    switch (pgm_read_byte(&r->kind)) {
    case K_FLOAT: memcpy(value, field, sizeof(*value)); break;
    case K_U8: *value = *field; break;
    case K_U16:
        memcpy(&w, field, sizeof(w));
        *value = w;
        break;
    default: *value = pgm_read_word(&r->limit); break;
    }
    return 1;
}

uint8_t settings_checksum(const uint8_t *data, uint16_t len)
{
    /* rotate-and-add: catches swapped bytes that a plain sum misses */
    uint8_t sum = 0x5A;
    for (uint16_t i = 0; i < len; i++)
        sum = (uint8_t)(((sum << 1) | (sum >> 7)) + data[i]);
    return sum;
}
