#include "timer_fix.h"

#include <stdio.h>
#include <string.h>

#include "avr_timer.h"
#include "sim_core.h"

#define MAX_TIMERS 4
enum { HOOK_MASK, HOOK_CLOCK, HOOK_COUNT_LO, HOOK_COUNT_HI, HOOKS_PER_TIMER };

struct hook {
	avr_io_write_t orig;
	void *orig_param;
	struct timer_state *ts;
	int kind;
};

struct timer_state {
	avr_timer_t *t;
	int preset_valid;          /* TCNT written while stopped */
	uint8_t preset_lo, preset_hi;
	struct hook hooks[HOOKS_PER_TIMER];
};

static struct timer_state timers[MAX_TIMERS];

static int clock_running(avr_t *avr, avr_timer_t *t)
{
	for (int i = 0; i < 4; i++)
		if (t->cs[i].reg && avr_regbit_get(avr, t->cs[i]))
			return 1;
	return 0;
}

static void raise_if_flagged(avr_t *avr, avr_int_vector_t *v)
{
	if (v->vector && !v->pending && v->raised.reg && v->enable.reg &&
	    avr_regbit_get(avr, v->raised) && avr_regbit_get(avr, v->enable))
		avr_raise_interrupt(avr, v);
}

static uint16_t ocr_a(avr_t *avr, avr_timer_t *t)
{
	uint16_t v = avr->data[t->comp[0].r_ocr];
	if (t->comp[0].r_ocrh)
		v |= (uint16_t)(avr->data[t->comp[0].r_ocrh] << 8);
	return v;
}

static void write_through(avr_t *avr, struct hook *h, avr_io_addr_t addr, uint8_t v)
{
	if (h->orig)
		h->orig(avr, addr, v, h->orig_param);
	else
		avr->data[addr] = v;
}

static void hooked_write(avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
	struct hook *h = param;
	struct timer_state *ts = h->ts;
	avr_timer_t *t = ts->t;
	int was_running = clock_running(avr, t);
	if ((h->kind == HOOK_COUNT_LO || h->kind == HOOK_COUNT_HI) && !was_running) {
		if (h->kind == HOOK_COUNT_HI)
			ts->preset_hi = v;
		else {
			ts->preset_lo = v;
			ts->preset_valid = 1;
		}
	}
	write_through(avr, h, addr, v);
	if (h->kind == HOOK_CLOCK && !was_running && clock_running(avr, t)) {
		if (ts->preset_valid) {
			struct hook *lo = &ts->hooks[HOOK_COUNT_LO];
			if (t->r_tcnth)
				avr->data[t->r_tcnth] = ts->preset_hi;
			write_through(avr, lo, t->r_tcnt, ts->preset_lo);
		}
		if (t->mode.kind == avr_timer_wgm_ctc && ocr_a(avr, t) == 0)
			avr_raise_interrupt(avr, &t->comp[0].interrupt);
	}
	if (h->kind == HOOK_CLOCK || h->kind == HOOK_COUNT_LO)
		ts->preset_valid = ts->preset_valid && !clock_running(avr, t);
	if (h->kind == HOOK_MASK) {
		for (int i = 0; i < AVR_TIMER_COMP_COUNT; i++)
			raise_if_flagged(avr, &t->comp[i].interrupt);
		raise_if_flagged(avr, &t->overflow);
		raise_if_flagged(avr, &t->icr);
	}
}

static void hook(avr_t *avr, struct timer_state *ts, int kind, avr_io_addr_t addr)
{
	if (!addr || addr < 32 || addr >= 32 + MAX_IOs)
		return;
	struct hook *h = &ts->hooks[kind];
	int io = AVR_DATA_TO_IO(addr);
	h->orig = avr->io[io].w.c;
	h->orig_param = avr->io[io].w.param;
	h->ts = ts;
	h->kind = kind;
	avr->io[io].w.c = hooked_write;
	avr->io[io].w.param = h;
}

void timer_fix_install(avr_t *avr)
{
	int n = 0;
	for (avr_io_t *io = avr->io_port; io && n < MAX_TIMERS; io = io->next) {
		if (!io->kind || strcmp(io->kind, "timer") != 0)
			continue;
		struct timer_state *ts = &timers[n++];
		memset(ts, 0, sizeof *ts);
		ts->t = (avr_timer_t *)io;
		hook(avr, ts, HOOK_MASK, ts->t->overflow.enable.reg);
		hook(avr, ts, HOOK_CLOCK, ts->t->cs[0].reg);
		hook(avr, ts, HOOK_COUNT_LO, ts->t->r_tcnt);
		hook(avr, ts, HOOK_COUNT_HI, ts->t->r_tcnth);
	}
}
