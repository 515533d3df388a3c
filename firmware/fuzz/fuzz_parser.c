/* libFuzzer target: any byte stream through line assembly, the G-code and
 * $ parsers, arc cutting, the planner and the segment preparer, exactly as
 * the firmware's main loop feeds them (host build of the same sources).
 * `make fuzz` runs it under libFuzzer; `make test` replays the corpus and
 * pseudo-random inputs through it under ASan/UBSan with gcc. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include "arc.h"
#include "gcode.h"
#include "linebuf.h"
#include "numparse.h"
#include "plan_split.h"
#include "planner.h"
#include "segment.h"
#include "settings.h"

#define FUZZ_ARC_POINTS 64 /* enough to exercise arcs, few enough to stay fast */
#define FUZZ_MAX_SEGMENTS 20000 /* a 10 m move at a crawl is millions of segments: stop there */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static uint32_t segments;

static void drain_segments(void)
{
    seg_fill();
    segments += (uint8_t)(seg_head - seg_tail);
    seg_tail = seg_head; /* the step interrupt would consume them */
    if (segments > FUZZ_MAX_SEGMENTS) { /* as a soft reset would: forget the queue */
        plan_reset();
        seg_reset();
        segments = 0;
    }
}

/* plan_line_split's wait for room, as the firmware's: the step interrupt
 * would free blocks; a move of more than 64 pieces is given up there (as
 * an abort would), which keeps a huge one fast */
static uint8_t pieces_left;
static uint8_t room(void)
{
    drain_segments();
    while (!plan_free())
        drain_segments();
    return pieces_left-- != 0;
}

/* as the firmware's line_to: long moves in pieces the step counters can hold */
static void queue_line(const float *target, float feed, uint8_t flags)
{
    pieces_left = 65; /* the first room() is before plan_line finds out whether it fits */
    plan_line_split(target, feed, flags, room);
    drain_segments();
}

static void run_block(const gc_block_t *b)
{
    switch (b->action) {
    case ACT_RAPID: queue_line(b->target, 0, PB_RAPID); break;
    case ACT_LINE: queue_line(b->target, b->feed, 0); break;
    case ACT_G28:
        if (b->has_via)
            queue_line(b->via, 0, PB_RAPID);
        queue_line(b->target, 0, PB_RAPID);
        break;
    case ACT_ARC: {
        arc_t arc;
        if (arc_init(&arc, b->start, b->target, b->center, b->clockwise, settings.arc_tolerance))
            break;
        uint16_t step = arc.segments > FUZZ_ARC_POINTS ? arc.segments / FUZZ_ARC_POINTS : 1;
        for (uint16_t k = step; ; k += step) {
            float p[N_AXIS];
            arc_point(&arc, k >= arc.segments ? arc.segments : k, p);
            queue_line(p, b->feed, 0);
            if (k >= arc.segments)
                break;
        }
        break;
    }
    default: break;
    }
}

static void run_dollar(const char *line)
{
    if (line[1] == 'J' && line[2] == '=') {
        gc_state_t tmp, undo;
        gc_block_t b;
        gc_init(&tmp);
        if (gc_parse(line + 3, &tmp, &b, 1, &undo) == 0)
            run_block(&b);
        return;
    }
    uint8_t i = 1;
    float id, value;
    if (read_number(line, &i, &id) && line[i] == '=') {
        i++;
        if (read_number(line, &i, &value) && id >= 0 && id < 256) {
            settings_t s = settings;
            settings_set(&s, (uint8_t)id, value);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static linebuf_t lb;
    static gc_state_t gc;
    settings_defaults(&settings);
    segments = 0;
    plan_reset();
    seg_reset();
    int32_t zero[N_AXIS] = {0, 0};
    plan_set_position(zero);
    linebuf_reset(&lb);
    gc_init(&gc);
    for (size_t n = 0; n <= size; n++) {
        uint8_t c = n < size ? data[n] : '\n';
        if (linebuf_feed(&lb, c) != LB_LINE)
            continue;
        if (lb.text[0] == '$') {
            run_dollar(lb.text);
            continue;
        }
        gc_state_t undo;
        gc_block_t b;
        if (gc_parse(lb.text, &gc, &b, 0, &undo) == 0)
            run_block(&b);
        else
            gc_undo(&gc, &undo, &b);
    }
    return 0;
}
