#include <string.h>
#include "settings.h"
#include "status.h"

settings_t settings;

const uint8_t settings_ids[] = {0, 1, 2, 3, 4, 5, 6, 10, 11, 12, 13, 20, 21, 22, 23, 24, 25, 26, 27,
                                30, 31, 32, 60, 61, 62, 63, 100, 101, 102, 110, 111, 112,
                                120, 121, 122, 130, 131, 132};
const uint8_t settings_count = sizeof(settings_ids);

void settings_defaults(settings_t *s)
{
    memset(s, 0, sizeof(*s));
    for (uint8_t i = 0; i < N_AXIS; i++) {
        s->steps_per_mm[i] = DEFAULT_STEPS_PER_MM;
        s->max_rate[i] = DEFAULT_MAX_RATE;
        s->accel[i] = DEFAULT_ACCEL;
    }
    s->max_travel[0] = DEFAULT_TRAVEL_X;
    s->max_travel[1] = DEFAULT_TRAVEL_Y;
    s->junction_deviation = 0.02f;
    s->arc_tolerance = 0.002f;
    s->homing_feed = 300.0f;
    s->homing_seek = 3000.0f;
    s->homing_pulloff = 1.0f;
    s->homing_debounce_ms = 25;
    s->pen_up_us = 1000;
    s->pen_down_us = 2000;
    s->pen_settle_ms = 150;
    s->pulse_us = 4;
    s->idle_delay_ms = 255;
    s->report_mask = 3;
    s->soft_limits = DEFAULT_HOMING; /* the board header: switches or not */
    s->hard_limits = DEFAULT_HOMING;
    s->homing_enable = DEFAULT_HOMING;
    s->homing_dir_mask = 3;
}

/* Each id maps to one field; floats and small integers are kept apart so
 * that range checks live in one place. */
static float *float_field(settings_t *s, uint8_t id)
{
    switch (id) {
    case 11: return &s->junction_deviation;
    case 12: return &s->arc_tolerance;
    case 24: return &s->homing_feed;
    case 25: return &s->homing_seek;
    case 27: return &s->homing_pulloff;
    case 100: case 101: return &s->steps_per_mm[id - 100];
    case 110: case 111: return &s->max_rate[id - 110];
    case 120: case 121: return &s->accel[id - 120];
    case 130: case 131: return &s->max_travel[id - 130];
    default: return 0;
    }
}

static uint8_t *byte_field(settings_t *s, uint8_t id)
{
    switch (id) {
    case 0: return &s->pulse_us;
    case 1: return &s->idle_delay_ms;
    case 2: return &s->step_invert;
    case 3: return &s->dir_invert;
    case 4: return &s->enable_invert;
    case 5: return &s->limit_invert;
    case 10: return &s->report_mask;
    case 13: return &s->report_inches;
    case 20: return &s->soft_limits;
    case 21: return &s->hard_limits;
    case 22: return &s->homing_enable;
    case 23: return &s->homing_dir_mask;
    case 63: return &s->corexy;
    default: return 0;
    }
}

static uint16_t *word_field(settings_t *s, uint8_t id)
{
    switch (id) {
    case 26: return &s->homing_debounce_ms;
    case 60: return &s->pen_up_us;
    case 61: return &s->pen_down_us;
    case 62: return &s->pen_settle_ms;
    default: return 0;
    }
}

/* Rows senders list that a pen plotter has no use for, with fixed values:
 * $6 probe invert, $30/$31 spindle range (S words are ignored), $32 laser
 * mode, and the Z axis (the pen servo, not a motor) $102 $112 $122 $132. */
static uint8_t fixed_value(uint8_t id, float *value)
{
    switch (id) {
    case 6: case 31: case 32: *value = 0.0f; return 1;
    case 30: *value = 1000.0f; return 1;
    case 102: case 122: *value = 100.0f; return 1;
    case 112: *value = 1000.0f; return 1;
    case 132: *value = 10.0f; return 1;
    default: return 0;
    }
}

uint8_t settings_is_integer(uint8_t id) { return float_field(&settings, id) == 0 && id < 100; }

uint8_t settings_set(settings_t *s, uint8_t id, float value)
{
    if (value != value)
        return ERR_BAD_NUMBER;
    if (value < 0.0f)
        return ERR_NEGATIVE;
    float fixed;
    if (fixed_value(id, &fixed))
        return value > fixed - 0.001f && value < fixed + 0.001f ? STATUS_OK : ERR_INVALID_DOLLAR;
    if (id == 20 && value != 0.0f && !s->homing_enable)
        return ERR_SOFT_LIMIT_NO_HOME;
    float *f = float_field(s, id);
    if (f) {
        /* zero or absurd values would divide by zero or overflow step counts */
        if (value > 1.0e6f)
            return ERR_INVALID_DOLLAR;
        if (value == 0.0f && id != 27)
            return ERR_INVALID_DOLLAR;
        if (id >= 100 && id <= 101 && value > 2000.0f)
            return ERR_INVALID_DOLLAR;
        *f = value;
        return STATUS_OK;
    }
    if (value != (float)(uint32_t)value)
        return ERR_NOT_INTEGER;
    uint32_t v = (uint32_t)value;
    uint8_t *b = byte_field(s, id);
    if (b) {
        uint8_t max = 255;
        if (id == 2 || id == 3 || id == 5 || id == 23)
            max = 3;
        else if (id == 4 || id == 13 || id == 20 || id == 21 || id == 22 || id == 63)
            max = 1;
        else if (id == 10)
            max = 3;
        if (v > max)
            return ERR_INVALID_DOLLAR;
        if (id == 0 && v < 3)
            return ERR_STEP_PULSE;
        if (id == 0 && v > 12)  /* the pulse must fit well inside a 40 kHz period */
            return ERR_INVALID_DOLLAR;
        *b = (uint8_t)v;
        return STATUS_OK;
    }
    uint16_t *w = word_field(s, id);
    if (w) {
        if (id == 60 || id == 61) {
            if (v < 500 || v > 2500)
                return ERR_INVALID_DOLLAR;
        } else if (v > 10000) {
            return ERR_INVALID_DOLLAR;
        }
        *w = (uint16_t)v;
        return STATUS_OK;
    }
    return ERR_INVALID_DOLLAR;
}

uint8_t settings_get(const settings_t *s, uint8_t id, float *value)
{
    settings_t *m = (settings_t *)s; /* the field lookups do not write */
    if (fixed_value(id, value))
        return 1;
    float *f = float_field(m, id);
    if (f) {
        *value = *f;
        return 1;
    }
    uint8_t *b = byte_field(m, id);
    if (b) {
        *value = *b;
        return 1;
    }
    uint16_t *w = word_field(m, id);
    if (w) {
        *value = *w;
        return 1;
    }
    return 0;
}

uint8_t settings_checksum(const uint8_t *data, uint16_t len)
{
    /* rotate-and-add: catches swapped bytes that a plain sum misses */
    uint8_t sum = 0x5A;
    for (uint16_t i = 0; i < len; i++)
        sum = (uint8_t)(((sum << 1) | (sum >> 7)) + data[i]);
    return sum;
}
