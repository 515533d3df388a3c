/* Benchmark harness (bench/firmware_bench.py builds and runs it): runs a
 * firmware ELF in libsimavr, streams a G-code file into its UART with
 * character counting at the real byte rate, and measures in simulated
 * cycles: when each line is acknowledged, how long the step interrupt runs
 * (the bench build raises PC5 for the body of the step interrupt), and
 * the step rate per axis over 5 ms windows. Prints one JSON object. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "avr_extint.h"
#include "avr_ioport.h"
#include "avr_uart.h"
#include "sim_avr.h"
#include "sim_elf.h"
#include "sim_irq.h"

#define F_CPU 16000000ULL
#define WINDOW (F_CPU / 200)      /* 5 ms */
#define MAX_WINDOWS 20000
#define MAX_LINES 20000
#define RX_BUDGET 128
#define IDLE_END (F_CPU / 4)      /* no step for 250 ms after the last ack: done */

static avr_t *avr;
static char *text;
static size_t text_len, line_start[MAX_LINES];
static size_t line_count, acked, inflight;
static uint64_t ack_cycle[MAX_LINES];
static uint64_t last_byte_cycle[MAX_LINES]; /* when each line's newline went in */
static unsigned errors;
static uint64_t byte_cycles, next_byte_at;
static char outline[256];
static size_t outlen;
static uint64_t isr_rise, isr_max, isr_count, isr_total;
static uint64_t steps[2], last_step_cycle, last_rise[2], min_interval[2] = {~0ULL, ~0ULL};
static uint32_t window_steps[MAX_WINDOWS][2];
static int alarm_seen;
static uint64_t mark_rise, mark_total, mark_count, mark_max; /* PC4: the pulse-end interrupt */
/* Per step period (from one step interrupt to the next): its body, and the
 * pulse-end bodies that ran in it. The worst period with and without a
 * pulse-end interrupt: a tick long enough to outlast the pulse ends it
 * itself, so the longest ticks are not followed by the other interrupt. */
static uint64_t period_isr, period_mark, period_marks;
static uint64_t worst_alone, worst_pair_isr, worst_pair_mark;
/* HARNESS_PROFILE=FILE: sample the program counter every PROFILE_EVERY
 * cycles (odd, so no loop aliases with it) and write "byte_address count"
 * lines; bench/firmware_bench.py --profile maps them to functions. */
#define PROFILE_EVERY 97
#define FLASH_WORDS 131072 /* the 2560's 256 KiB (its image is past 32 KiB) */
static uint32_t *profile;
static size_t profile_from; /* HARNESS_PROFILE_FROM: first line acknowledged */

/* HARNESS_CALLS=FILE with HARNESS_CALLS_WATCH="byte_address,...": count the
 * calls of those functions by return address, with their cycles from entry
 * to return less the interrupts that came in between, and write "callee
 * return_byte_address calls cycles" lines; bench/firmware_bench.py --calls
 * maps them to the calling functions. */
#define CALL_SITES 4096
#define CALL_DEPTH 32
#define VECTORS 57 /* the 2560's; a call never goes below the last vector on the 328P either */
static uint8_t *watched; /* per flash word */
static struct call_site { uint32_t callee, ret; uint64_t calls, cycles; } sites[CALL_SITES];
static struct {
    uint32_t ret;
    uint16_t sp;
    uint8_t isr;
    uint64_t at, isr_at; /* the cycle, and isr_cycles, at entry */
    size_t site;
} calls[CALL_DEPTH];
static size_t call_depth, isr_depth;
static uint16_t last_sp;
static uint64_t isr_cycles, isr_from;

static uint16_t stack_pointer(void) { return (uint16_t)(avr->data[R_SPL] | avr->data[R_SPH] << 8); }

static void track_calls(void)
{
    uint32_t pc = avr->pc / 2;
    uint16_t sp = stack_pointer(), sp_before = last_sp;
    last_sp = sp;
    /* returned: at the return address with the stack back above it (SP
     * alone would not do: an epilogue writes SPH before SPL) */
    if (call_depth && pc == calls[call_depth - 1].ret && sp > calls[call_depth - 1].sp) {
        call_depth--;
        if (calls[call_depth].isr) {
            if (--isr_depth == 0)
                isr_cycles += avr->cycle - isr_from;
        } else {
            sites[calls[call_depth].site].cycles +=
                avr->cycle - calls[call_depth].at - (isr_cycles - calls[call_depth].isr_at);
        }
    }
    /* a call or an interrupt: the last instruction pushed just a return
     * address (a jump or a branch to a watched label is no call) */
    if (sp_before - sp != avr->address_size || call_depth == CALL_DEPTH)
        return;
    int wide = avr->address_size == 3;
    uint32_t ret = wide ? (uint32_t)avr->data[sp + 1] << 16 | avr->data[sp + 2] << 8 | avr->data[sp + 3]
                        : (uint32_t)avr->data[sp + 1] << 8 | avr->data[sp + 2];
    if (pc * 2 < VECTORS * avr->vector_size) {
        if (isr_depth++ == 0)
            isr_from = avr->cycle;
        calls[call_depth++] = (typeof(calls[0])){ret, sp, 1, 0, 0, 0};
        return;
    }
    if (!watched[pc] || acked < profile_from || acked >= line_count)
        return;
    size_t i = (pc * 31u + ret) % CALL_SITES, probes = 0;
    while (sites[i].calls && !(sites[i].callee == pc && sites[i].ret == ret)) {
        i = (i + 1) % CALL_SITES;
        if (++probes == CALL_SITES)
            return;
    }
    if (!sites[i].calls)
        sites[i] = (struct call_site){pc, ret, 0, 0};
    sites[i].calls++;
    calls[call_depth++] = (typeof(calls[0])){ret, sp, 0, avr->cycle, isr_cycles, i};
}

static avr_cycle_count_t sample_pc(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)param;
    if (acked >= profile_from && acked < line_count && a->pc / 2 < FLASH_WORDS)
        profile[a->pc / 2]++;
    return when + PROFILE_EVERY;
}

static void on_mark_pin(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (value & 1) {
        mark_rise = avr->cycle;
    } else if (mark_rise) {
        uint64_t d = avr->cycle - mark_rise;
        mark_total += d;
        mark_count++;
        period_mark += d;
        period_marks++;
        if (d > mark_max)
            mark_max = d;
    }
}

static void on_uart_out(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    char c = (char)value;
    if (c == '\n') {
        outline[outlen] = 0;
        if (outlen && outline[outlen - 1] == '\r')
            outline[outlen - 1] = 0;
        int is_ok = strcmp(outline, "ok") == 0, is_err = strncmp(outline, "error:", 6) == 0;
        if ((is_ok || is_err) && acked < line_count) {
            if (is_err) {
                errors++;
                fprintf(stderr, "line %zu: %s\n", acked + 1, outline);
            }
            size_t len = (acked + 1 < line_count ? line_start[acked + 1] : text_len) - line_start[acked];
            inflight -= len;
            ack_cycle[acked++] = avr->cycle;
        } else if (strncmp(outline, "ALARM", 5) == 0) {
            alarm_seen = 1;
            fprintf(stderr, "%s\n", outline);
        }
        outlen = 0;
    } else if (outlen < sizeof(outline) - 1) {
        outline[outlen++] = c;
    }
}

static void on_step(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    int axis = (int)(intptr_t)param;
    if (!(value & 1))
        return;
    uint64_t now = avr->cycle;
    if (steps[axis] && now - last_rise[axis] < min_interval[axis])
        min_interval[axis] = now - last_rise[axis];
    last_rise[axis] = now;
    steps[axis]++;
    last_step_cycle = now;
    uint64_t w = now / WINDOW;
    if (w < MAX_WINDOWS)
        window_steps[w][axis]++;
}

static void close_period(void)
{
    if (period_marks && period_isr + period_mark > worst_pair_isr + worst_pair_mark) {
        worst_pair_isr = period_isr;
        worst_pair_mark = period_mark;
    } else if (!period_marks && period_isr > worst_alone) {
        worst_alone = period_isr;
    }
    period_isr = period_mark = period_marks = 0;
}

static void on_isr_pin(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (value & 1) {
        close_period();
        isr_rise = avr->cycle;
        return;
    }
    if (!isr_rise)
        return; /* the pin settling at start-up, not an interrupt */
    uint64_t d = avr->cycle - isr_rise;
    period_isr = d;
    isr_count++;
    isr_total += d;
    if (d > isr_max)
        isr_max = d;
    if (getenv("HARNESS_ISR_DEBUG") && d > 1000)
        fprintf(stderr, "long isr %llu cycles at %llu\n", (unsigned long long)d, (unsigned long long)isr_rise);
}

/* one byte per character time; a line starts only when all of it fits in
 * the receive buffer next to the lines not yet acknowledged */
static size_t next_line, pos_in_line;

static size_t line_len(size_t i)
{
    return (i + 1 < line_count ? line_start[i + 1] : text_len) - line_start[i];
}

static avr_cycle_count_t feed(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)param;
    if (next_line < line_count) {
        if (pos_in_line == 0 && inflight + line_len(next_line) <= RX_BUDGET)
            inflight += line_len(next_line);
        else if (pos_in_line == 0)
            return when + byte_cycles / 4; /* wait for an ok */
        avr_raise_irq(avr_io_getirq(a, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT),
                      (uint8_t)text[line_start[next_line] + pos_in_line]);
        if (++pos_in_line == line_len(next_line)) {
            last_byte_cycle[next_line] = a->cycle;
            pos_in_line = 0;
            next_line++;
        }
    }
    return when + byte_cycles;
}

/* Simulated sleep. simavr skips a sleeping CPU ahead to its next timer
 * event inside avr_run and reports each jump here (the CPU then sits 1 +
 * how_long cycles); this also replaces simavr's default, which calls
 * usleep() to keep pace with the wall clock. Counting here rather than
 * around avr_run: the call that executes the SLEEP instruction already
 * jumps ahead, and a test of the state before the call missed that whole
 * first stretch (without other cycle timers, most of every sleep).
 * HARNESS_SPAN_FROM=N: also count the sleep from the Nth acknowledgement
 * to the last one (the CPU's idle share of a measured run). */
static uint64_t sleep_cycles, span_sleep_cycles;
static size_t span_from;

static void count_sleep(avr_t *a, avr_cycle_count_t how_long)
{
    (void)a;
    sleep_cycles += 1 + how_long;
    if (acked >= span_from && acked < line_count)
        span_sleep_cycles += 1 + how_long;
}

/* A pin from the environment as PORT LETTER and bit ("D2"), or the default. */
static avr_irq_t *pin_irq(const char *env, char port, int bit)
{
    const char *v = getenv(env);
    if (v && v[0] >= 'A' && v[0] <= 'L' && v[1] >= '0' && v[1] <= '7') {
        port = v[0];
        bit = v[1] - '0';
    }
    return avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(port), bit);
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: %s FIRMWARE.elf GCODE [max_seconds]\n", argv[0]);
        return 2;
    }
    double max_s = argc > 3 ? atof(argv[3]) : 120.0;
    FILE *f = fopen(argv[2], "rb");
    if (!f)
        return 2;
    text = malloc(1 << 24);
    text_len = fread(text, 1, (1 << 24) - 1, f);
    fclose(f);
    for (size_t i = 0; i < text_len && line_count < MAX_LINES; i++)
        if (i == 0 || text[i - 1] == '\n')
            line_start[line_count++] = i;

    elf_firmware_t fw;
    memset(&fw, 0, sizeof(fw));
    if (elf_read_firmware(argv[1], &fw))
        return 2;
    /* HARNESS_MCU, HARNESS_STEP_X/_Y, HARNESS_ISR_PIN, HARNESS_MARK_PIN: another
     * board profile (the defaults are the Uno CNC shield's) */
    const char *mcu = getenv("HARNESS_MCU");
    avr = avr_make_mcu_by_name(mcu ? mcu : "atmega328p");
    if (!avr)
        return 2;
    avr_init(avr);
    avr->frequency = F_CPU;
    avr->log = 0;
    avr_load_firmware(avr, &fw);
    /* simavr polls INT0/INT1 (the step pins) on every cycle otherwise */
    avr_extint_set_strict_lvl_trig(avr, 0, 0);
    avr_extint_set_strict_lvl_trig(avr, 1, 0);
    /* no flow control: the harness paces itself */
    uint32_t flags = 0;
    avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
    flags &= ~AVR_UART_FLAG_STDIO;
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), on_uart_out, 0);
    avr_irq_register_notify(pin_irq("HARNESS_STEP_X", 'D', 2), on_step, (void *)0);
    avr_irq_register_notify(pin_irq("HARNESS_STEP_Y", 'D', 3), on_step, (void *)1);
    avr_irq_register_notify(pin_irq("HARNESS_ISR_PIN", 'C', 5), on_isr_pin, 0);
    avr_irq_register_notify(pin_irq("HARNESS_MARK_PIN", 'C', 4), on_mark_pin, 0);

    /* the firmware runs U2X with UBRR 16: 117647 baud. simavr's UART takes
     * input bytes a little slower than 10 bits each and drops what overflows
     * its FIFO, so pace at 11 bits a byte (HARNESS_BYTE_BITS: slower, for
     * bench/line_time.py, which has each line meet an idle main loop). */
    const char *bits = getenv("HARNESS_BYTE_BITS");
    byte_cycles = (bits && atoi(bits) > 11 ? (uint64_t)atoi(bits) : 11ULL) * 8ULL * 17ULL;
    next_byte_at = F_CPU / 5; /* after the banner and the EEPROM defaults */
    avr_cycle_timer_register(avr, next_byte_at, feed, 0);

    const char *profile_path = getenv("HARNESS_PROFILE");
    if (profile_path) {
        profile = calloc(FLASH_WORDS, sizeof(*profile));
        const char *from = getenv("HARNESS_PROFILE_FROM");
        profile_from = from ? (size_t)atol(from) : 0;
        avr_cycle_timer_register(avr, PROFILE_EVERY, sample_pc, 0);
    }

    const char *calls_path = getenv("HARNESS_CALLS");
    if (calls_path) {
        watched = calloc(FLASH_WORDS, 1);
        const char *from = getenv("HARNESS_PROFILE_FROM");
        profile_from = from ? (size_t)atol(from) : 0;
        for (const char *w = getenv("HARNESS_CALLS_WATCH"); w && *w;) {
            char *end;
            unsigned long addr = strtoul(w, &end, 0);
            if (end == w)
                break;
            if (addr / 2 < FLASH_WORDS)
                watched[addr / 2] = 1;
            w = *end ? end + 1 : end;
        }
    }

    uint64_t limit = (uint64_t)(max_s * F_CPU);
    const char *span_env = getenv("HARNESS_SPAN_FROM");
    span_from = span_env ? (size_t)atol(span_env) : (size_t)-1;
    avr->sleep = count_sleep;
    for (;;) {
        if (watched)
            track_calls();
        int st = avr_run(avr);
        if (st == cpu_Done || st == cpu_Crashed)
            break;
        if (avr->cycle > limit)
            break;
        if (acked == line_count && avr->cycle > last_step_cycle + IDLE_END &&
            avr->cycle > ack_cycle[line_count - 1] + IDLE_END)
            break;
    }
    if (profile_path) {
        FILE *pf = fopen(profile_path, "w");
        for (uint32_t w = 0; pf && w < FLASH_WORDS; w++)
            if (profile[w])
                fprintf(pf, "%u %u\n", w * 2, profile[w]);
        if (pf)
            fclose(pf);
    }
    if (calls_path) {
        FILE *cf = fopen(calls_path, "w");
        for (size_t i = 0; cf && i < CALL_SITES; i++)
            if (sites[i].calls)
                fprintf(cf, "%u %u %llu %llu\n", sites[i].callee * 2, sites[i].ret * 2,
                    (unsigned long long)sites[i].calls, (unsigned long long)sites[i].cycles);
        if (cf)
            fclose(cf);
    }
    printf("{\"sleep_cycles\": %llu, \"span_sleep_cycles\": %llu, ", (unsigned long long)sleep_cycles,
           (unsigned long long)span_sleep_cycles);
    printf("\"cycles\": %llu, \"lines\": %zu, \"acked\": %zu, \"errors\": %u, \"alarm\": %d,\n",
           (unsigned long long)avr->cycle, line_count, acked, errors, alarm_seen);
    printf(" \"isr\": {\"count\": %llu, \"max_cycles\": %llu, \"mean_cycles\": %.1f},\n",
           (unsigned long long)isr_count, (unsigned long long)isr_max,
           isr_count ? (double)isr_total / (double)isr_count : 0.0);
    close_period(); /* the last one */
    printf(" \"period\": {\"worst_alone\": %llu, \"worst_pair_isr\": %llu, \"worst_pair_mark\": %llu},\n",
           (unsigned long long)worst_alone, (unsigned long long)worst_pair_isr,
           (unsigned long long)worst_pair_mark);
    printf(" \"mark\": {\"count\": %llu, \"total_cycles\": %llu, \"max_cycles\": %llu},\n",
           (unsigned long long)mark_count, (unsigned long long)mark_total, (unsigned long long)mark_max);
    printf(" \"steps\": [%llu, %llu], \"min_interval_cycles\": [%llu, %llu],\n",
           (unsigned long long)steps[0], (unsigned long long)steps[1],
           (unsigned long long)(steps[0] > 1 ? min_interval[0] : 0),
           (unsigned long long)(steps[1] > 1 ? min_interval[1] : 0));
    printf(" \"last_byte_cycles\": [");
    for (size_t i = 0; i < line_count; i++)
        printf("%s%llu", i ? "," : "", (unsigned long long)last_byte_cycle[i]);
    printf("],");
    printf(" \"ack_cycles\": [");
    for (size_t i = 0; i < acked; i++)
        printf("%s%llu", i ? "," : "", (unsigned long long)ack_cycle[i]);
    printf("],\n \"window_cycles\": %llu, \"windows\": [", (unsigned long long)WINDOW);
    uint64_t nw = avr->cycle / WINDOW + 1;
    if (nw > MAX_WINDOWS)
        nw = MAX_WINDOWS;
    for (uint64_t w = 0; w < nw; w++)
        printf("%s[%u,%u]", w ? "," : "", window_steps[w][0], window_steps[w][1]);
    printf("]}\n");
    return 0;
}
