/* plotsim: the real firmware ELF on a simulated ATmega328P or ATmega2560 at
 * 16 MHz, wired as a board profile (--board) to a plotter model. The loop
 * runs instructions in slices and, between slices, services the pty and the
 * control socket, paces simulated time against the wall clock, and keeps the
 * trace and EEPROM current; the trace file is written by a thread of its own
 * (file_writer.h). */
#include <elf.h>
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "sim_avr.h"
#include "sim_elf.h"

#include "control.h"
#include "board_pins.h"
#include "eeprom_file.h"
#include "file_writer.h"
#include "machine.h"
#include "options.h"
#include "peek.h"
#include "pins.h"
#include "pty_link.h"
#include "reset_fix.h"
#include "timer_fix.h"
#include "trace_out.h"

#define CPU_HZ 16000000u
/* cycles between looks at the wall clock (0.25 ms simulated); system calls
 * (pty, control socket) happen only every IO_INTERVAL of wall time */
#define SLICE_CYCLES 4000u
#define TRACE_MIN_INTERVAL 0.05  /* 20 writes a second at most */
#define EEPROM_CHECK_INTERVAL 0.1
#define IO_INTERVAL 0.0005       /* look at the pty and control socket (wall s) */
#define MIN_SLEEP 0.0002         /* don't sleep for less than this (wall s) */
#define MAX_LAG 0.25             /* fell behind more than this: stop catching up */

static volatile sig_atomic_t stop_requested;

static void on_signal(int sig)
{
	(void)sig;
	stop_requested = 1;
}

struct sim {
	struct options opt;
	const struct board_pins *board;
	avr_t *avr;
	struct machine mc;
	struct pins pins;
	struct pty_link pty;
	struct control ctl;
	struct eeprom_file ee;
	struct file_writer trace_file;
	double last_step_mono;
	double trace_due, trace_interval;
	int quit;
};

static double monotonic(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void no_sleep(avr_t *avr, avr_cycle_count_t how_long)
{
	/* pacing is the loop's job; simavr would usleep() here */
	(void)avr;
	(void)how_long;
}

static void write_json(struct sim *s, FILE *f, int newline)
{
	struct trace_meta meta = {
		.sim_time = (double)s->avr->cycle / CPU_HZ,
		.last_step_monotonic = s->last_step_mono,
		.newline = newline,
	};
	trace_write_json(f, &s->mc, &meta);
}

/* the trace JSON or SVG as text in memory (malloc'd, *len bytes), or NULL */
static char *render(struct sim *s, int svg, size_t *len)
{
	char *buf = NULL;
	FILE *f = open_memstream(&buf, len);
	if (!f)
		return NULL;
	if (svg)
		trace_write_svg(f, &s->mc);
	else
		write_json(s, f, 1);
	if (fclose(f) != 0) {
		free(buf);
		return NULL;
	}
	return buf;
}

/* the SVG a control request asks for, written before the answer */
static int write_svg(struct sim *s, const char *path)
{
	size_t len;
	char *svg = render(s, 1, &len);
	int r = svg ? file_write_atomic(path, svg, len) : -1;
	free(svg);
	return r;
}

/* the trace file: rendered here, written by the trace file's own thread */
static void write_trace(struct sim *s)
{
	if (!s->opt.trace)
		return;
	double t0 = monotonic();
	size_t len;
	char *json = render(s, 0, &len);
	if (json)
		file_writer_put(&s->trace_file, json, len);
	else
		fprintf(stderr, "plotsim: cannot render the trace: %s\n", strerror(errno));
	/* a huge trace must not eat the simulation: at most ~10% of the time */
	double took = monotonic() - t0;
	s->trace_interval = took * 10 > TRACE_MIN_INTERVAL ? took * 10 : TRACE_MIN_INTERVAL;
	s->mc.changed = 0;
}

static int button_named(const char *name)
{
	static const char *const names[BUTTON_COUNT] = { "estop", "pause", "resume" };
	for (int i = 0; i < BUTTON_COUNT; i++)
		if (strcmp(name, names[i]) == 0)
			return i;
	return -1;
}

static void handle_command(void *ctx, const char *line, FILE *reply)
{
	struct sim *s = ctx;
	char cmd[16] = "", arg[CONTROL_LINE_MAX] = "";
	if (sscanf(line, " %15s %1023[^\n]", cmd, arg) < 1) {
		fputs("error: empty command\n", reply);
		return;
	}
	if (strcmp(cmd, "press") == 0 || strcmp(cmd, "release") == 0) {
		int b = button_named(arg);
		if (b < 0) {
			fprintf(reply, "error: unknown button '%s' (estop, pause, resume)\n", arg);
			return;
		}
		if (pins_set_button(&s->pins, b, cmd[0] == 'p') < 0)
			fprintf(reply, "error: board %s has no %s button\n", s->board->name, arg);
		else
			fputs("ok\n", reply);
	} else if (strcmp(cmd, "trace") == 0) {
		write_json(s, reply, 1);
	} else if (strcmp(cmd, "svg") == 0) {
		if (!arg[0])
			fputs("error: svg needs a PATH\n", reply);
		else if (write_svg(s, arg) < 0)
			fprintf(reply, "error: cannot write %s: %s\n", arg, strerror(errno));
		else
			fputs("ok\n", reply);
	} else if (strcmp(cmd, "clear") == 0) {
		machine_clear(&s->mc, s->avr->cycle);
		fputs("ok\n", reply);
	} else if (strcmp(cmd, "peek") == 0) {
		peek_reply(s->avr, arg, reply);
	} else if (strcmp(cmd, "quit") == 0) {
		s->quit = 1;
		fputs("ok\n", reply);
	} else {
		fprintf(reply, "error: unknown command '%s' (press, release, trace, svg, clear, peek, quit)\n",
			cmd);
	}
}

/* Waits up to `seconds` (0: just looks) for pty or control socket activity
 * and services what is ready: one system call when nothing is. */
static void io_tick(struct sim *s, double seconds)
{
	struct pollfd fds[1 + 1 + CONTROL_MAX_CLIENTS];
	int n = 0;
	fds[n++] = (struct pollfd){ .fd = s->pty.master, .events = POLLIN };
	n += control_pollfds(&s->ctl, fds + n, (int)(sizeof fds / sizeof fds[0]) - n);
	struct timespec ts = { .tv_sec = (time_t)seconds,
			       .tv_nsec = (long)((seconds - (double)(time_t)seconds) * 1e9) };
	if (ppoll(fds, (nfds_t)n, &ts, NULL) < 0)
		return;
	/* pending output is written (or dropped) whether or not the pty said so */
	if (fds[0].revents || pty_link_pending_tx(&s->pty))
		pty_link_service(&s->pty);
	for (int i = 1; i < n; i++) {
		if (fds[i].revents) {
			control_service(&s->ctl, handle_command, s);
			break;
		}
	}
}

static int run(struct sim *s)
{
	avr_t *avr = s->avr;
	double wall0 = monotonic();
	avr_cycle_count_t cycle0 = avr->cycle;
	double next_eeprom = wall0 + EEPROM_CHECK_INTERVAL;
	double next_io = wall0;
	s->trace_due = wall0;
	while (!stop_requested && !s->quit) {
		avr_cycle_count_t until = avr->cycle + SLICE_CYCLES;
		while (avr->cycle < until) {
			int state = avr_run(avr);
			if (state == cpu_Done || state == cpu_Crashed) {
				fprintf(stderr, "plotsim: the firmware stopped (%s) at pc 0x%05x\n",
					state == cpu_Done ? "sleep with interrupts off" : "crashed",
					(unsigned)avr->pc);
				return 3;
			}
		}
		double now = monotonic();
		if (s->mc.stepped) {
			s->mc.stepped = 0;
			s->last_step_mono = now;
		}
		if (now >= next_io) {
			io_tick(s, 0);
			next_io = now + IO_INTERVAL;
		}
		if (s->mc.changed && now >= s->trace_due) {
			write_trace(s);
			s->trace_due = now + s->trace_interval;
		}
		if (now >= next_eeprom) {
			eeprom_file_sync(&s->ee, avr);
			next_eeprom = now + EEPROM_CHECK_INTERVAL;
		}
		if (s->opt.speed > 0) {
			double sim_elapsed = (double)(avr->cycle - cycle0) / CPU_HZ;
			double wall_needed = sim_elapsed / s->opt.speed;
			double ahead = wall_needed - (now - wall0);
			if (ahead > MIN_SLEEP)
				io_tick(s, ahead);
			else if (ahead < -MAX_LAG) {
				wall0 = now - wall_needed;
			}
		}
	}
	return 0;
}

/* simavr's loader trusts its input (another architecture's ELF crashes it):
 * check the header first */
static int check_elf(const char *path, char *err, size_t errlen)
{
	Elf32_Ehdr h;
	FILE *f = fopen(path, "rb");
	if (!f) {
		snprintf(err, errlen, "%s: %s", path, strerror(errno));
		return -1;
	}
	size_t n = fread(&h, 1, sizeof h, f);
	fclose(f);
	if (n != sizeof h || memcmp(h.e_ident, ELFMAG, SELFMAG) != 0 ||
	    h.e_ident[EI_CLASS] != ELFCLASS32 || h.e_ident[EI_DATA] != ELFDATA2LSB) {
		snprintf(err, errlen, "%s: not an ELF file for a 32-bit little-endian target", path);
		return -1;
	}
	if (h.e_machine != EM_AVR) {
		snprintf(err, errlen, "%s: an ELF file for machine %u, not AVR", path,
			 (unsigned)h.e_machine);
		return -1;
	}
	return 0;
}

/* The bootloader's Intel HEX into the flash, and the reset vector at its
 * lowest address (the BOOTRST fuse, which simavr does not model). The chip
 * then programs itself with SPM as avrdude talks to it over the pty.
 * (simavr's own HEX reader rejects the start-address records in Arduino's
 * bootloader files, so this reads them: data 00, end 01, segment 02,
 * start 03/05 ignored, linear 04.) */
static int load_bootloader(avr_t *avr, const char *path, unsigned flash_bytes, char *err,
			   size_t errlen)
{
	FILE *f = fopen(path, "r");
	if (!f) {
		snprintf(err, errlen, "--bootloader %s: %s", path, strerror(errno));
		return -1;
	}
	char line[600];
	uint32_t base = 0, start = UINT32_MAX;
	int n = 0, bad = 0;
	while (!bad && fgets(line, sizeof line, f)) {
		n++;
		unsigned len, addr, type, byte, sum = 0;
		if (line[0] != ':' || sscanf(line + 1, "%2x%4x%2x", &len, &addr, &type) != 3 ||
		    strlen(line) < 11 + 2 * len) {
			bad = 1;
			break;
		}
		uint8_t data[256];
		sum = len + (addr >> 8) + (addr & 0xff) + type;
		for (unsigned i = 0; i <= len; i++) { /* the data, then the checksum */
			sscanf(line + 9 + 2 * i, "%2x", &byte);
			sum += byte;
			if (i < len)
				data[i] = (uint8_t)byte;
		}
		if ((sum & 0xff) != 0) {
			bad = 1;
		} else if (type == 0) {
			/* Debian's optiboot_atmega328.hex (rebuilt with a newer gcc)
			 * is 20 bytes too long and spills past 0x7FFF; the chip's
			 * program counter wraps there, so the bytes go where it
			 * would fetch them: address modulo the flash size */
			for (unsigned i = 0; i < len; i++)
				avr->flash[(base + addr + i) % flash_bytes] = data[i];
			if (base + addr < start && base + addr < flash_bytes)
				start = base + addr;
		} else if (type == 2 && len == 2) {
			base = (uint32_t)((data[0] << 8) | data[1]) << 4;
		} else if (type == 4 && len == 2) {
			base = (uint32_t)((data[0] << 8) | data[1]) << 16;
		} else if (type == 1) {
			break;
		}
	}
	fclose(f);
	if (bad || start == UINT32_MAX) {
		snprintf(err, errlen, "--bootloader %s: line %d is not Intel HEX", path, n);
		return -1;
	}
	avr->reset_pc = start;
	avr->pc = start;
	avr->codeend = flash_bytes - 1;
	return 0;
}

static int setup(struct sim *s, char *err, size_t errlen)
{
	static elf_firmware_t fw;
	memset(&fw, 0, sizeof fw);
	s->board = board_pins_find(s->opt.board);
	if (!s->board) {
		snprintf(err, errlen, "--board %s: unknown board (%s)", s->opt.board, board_pins_names);
		return -1;
	}
	if (!s->opt.have_spm)
		s->opt.steps_per_mm = s->board->steps_per_mm;
	if (!s->opt.have_width)
		s->opt.width = s->board->width;
	if (!s->opt.have_height)
		s->opt.height = s->board->height;
	if (s->opt.firmware && check_elf(s->opt.firmware, err, errlen) < 0)
		return -1;
	if (s->opt.firmware && (elf_read_firmware(s->opt.firmware, &fw) < 0 || fw.flashsize == 0)) {
		snprintf(err, errlen, "%s: no program in this AVR ELF file", s->opt.firmware);
		return -1;
	}
	const struct board_pins *b = s->board;
	unsigned flash_kib = strcmp(b->mcu, "atmega2560") == 0 ? 256 : 32;
	if (fw.flashsize + fw.datasize > flash_kib * 1024) {
		snprintf(err, errlen, "%s: %u bytes of program do not fit the %u KiB flash",
			 s->opt.firmware, (unsigned)(fw.flashsize + fw.datasize), flash_kib);
		return -1;
	}
	if (fw.mmcu[0] && strcmp(fw.mmcu, b->mcu) != 0) {
		snprintf(err, errlen, "%s is built for %s, not %s (board %s)", s->opt.firmware,
			 fw.mmcu, b->mcu, b->name);
		return -1;
	}
	snprintf(fw.mmcu, sizeof fw.mmcu, "%s", b->mcu);
	fw.frequency = CPU_HZ;
	s->avr = avr_make_mcu_by_name(b->mcu);
	if (!s->avr || avr_init(s->avr) != 0) {
		snprintf(err, errlen, "simavr cannot create an %s", b->mcu);
		return -1;
	}
	if (s->opt.firmware)
		avr_load_firmware(s->avr, &fw);
	if (s->opt.bootloader && load_bootloader(s->avr, s->opt.bootloader, flash_kib * 1024, err,
						 errlen) < 0)
		return -1;
	s->avr->frequency = CPU_HZ;
	s->avr->sleep = no_sleep;
	/* simavr polls INT0/INT1 every cycle while PD2/PD3 (the step pins) are
	 * low, even with the interrupts disabled: 60% of the run time. This
	 * turns that off, now and after every reset of the chip. */
	reset_fix_install(s->avr);
	timer_fix_install(s->avr);
	if (eeprom_file_load(&s->ee, s->avr, s->opt.eeprom, err, errlen) < 0)
		return -1;

	struct machine_config cfg = {
		.freq = CPU_HZ, .width = s->opt.width, .height = s->opt.height,
		.steps_per_mm = s->opt.steps_per_mm, .corexy = s->opt.corexy,
		.pen_up_us = s->opt.pen_up_us, .pen_down_us = s->opt.pen_down_us,
		.max_step_rate = s->opt.max_step_rate, .coil_stride = b->coil_stride,
	};
	machine_init(&s->mc, &cfg, s->opt.start_x, s->opt.start_y);
	pins_attach(&s->pins, s->avr, &s->mc, b);
	if (pty_link_open(&s->pty, s->avr, s->opt.pty_link, err, errlen) < 0)
		return -1;
	if (control_open(&s->ctl, s->opt.control, err, errlen) < 0)
		return -1;
	return 0;
}

int main(int argc, char **argv)
{
	static struct sim s;
	char err[1200];
	int r = options_parse(argc, argv, &s.opt, err, sizeof err);
	if (r != 0) {
		if (r < 0)
			fprintf(stderr, "plotsim: %s\n%s", err, options_usage);
		return r < 0 ? 2 : 0;
	}
	/* Our stdout carries the protocol lines; simavr prints chatter on stdout,
	 * so its fd 1 goes to stderr and we keep a private handle. */
	fflush(stdout);
	int out_fd = dup(STDOUT_FILENO);
	FILE *out = out_fd >= 0 ? fdopen(out_fd, "w") : NULL;
	if (!out || dup2(STDERR_FILENO, STDOUT_FILENO) < 0) {
		perror("plotsim: stdout");
		return 2;
	}
	setvbuf(out, NULL, _IOLBF, 0);

	struct sigaction sa = { .sa_handler = on_signal };
	sigemptyset(&sa.sa_mask);
	sigaction(SIGTERM, &sa, NULL);
	sigaction(SIGINT, &sa, NULL);
	signal(SIGPIPE, SIG_IGN);

	s.pty.master = s.pty.slave = -1;
	s.ctl.listen_fd = -1;
	s.trace_interval = TRACE_MIN_INTERVAL;
	if (setup(&s, err, sizeof err) < 0) {
		fprintf(stderr, "plotsim: %s\n", err);
		pty_link_close(&s.pty);
		control_close(&s.ctl);
		return 2;
	}
	if (s.opt.trace && file_writer_start(&s.trace_file, s.opt.trace) < 0)
		fprintf(stderr, "plotsim: no thread for the trace file: written in the loop\n");
	write_trace(&s);
	fprintf(out, "plotsim: pty %s\n", s.pty.name);
	fprintf(out, "plotsim: ready\n");

	r = run(&s);

	write_trace(&s);
	file_writer_stop(&s.trace_file); /* the last trace on disk before the exit */
	if (eeprom_file_sync(&s.ee, s.avr) < 0)
		fprintf(stderr, "plotsim: cannot save the EEPROM to %s\n", s.ee.path);
	pty_link_close(&s.pty);
	control_close(&s.ctl);
	if (s.pty.dropped)
		fprintf(stderr, "plotsim: %llu bytes of firmware output had no reader\n",
			(unsigned long long)s.pty.dropped);
	machine_free(&s.mc);
	avr_terminate(s.avr);
	fclose(out);
	return r;
}
