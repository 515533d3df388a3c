#include "eeprom_file.h"
#include "file_writer.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "avr_eeprom.h"

/* The EEPROM module's own bytes. simavr's EEPROM ioctls differ between
 * versions in their bounds check and return value, so we go to the module. */
static avr_eeprom_t *sim_eeprom(avr_t *avr)
{
	for (avr_io_t *io = avr->io_port; io; io = io->next)
		if (io->kind && strcmp(io->kind, "eeprom") == 0)
			return (avr_eeprom_t *)io;
	return NULL;
}

int eeprom_file_load(struct eeprom_file *e, avr_t *avr, const char *path, char *err, size_t errlen)
{
	memset(e, 0, sizeof *e);
	avr_eeprom_t *ee = sim_eeprom(avr);
	if (!ee || !ee->eeprom || ee->size > EEPROM_MAX) {
		snprintf(err, errlen, "the simulated chip has no usable EEPROM");
		return -1;
	}
	if (!path || !*path)
		return 0;
	if (strlen(path) >= sizeof e->path) {
		snprintf(err, errlen, "--eeprom path too long");
		return -1;
	}
	snprintf(e->path, sizeof e->path, "%s", path);
	e->size = ee->size;
	memset(e->saved, 0xFF, e->size);
	FILE *f = fopen(path, "rb");
	if (f) {
		size_t n = fread(e->saved, 1, e->size, f);
		int extra = fgetc(f) != EOF;
		fclose(f);
		if (extra || (n != e->size && n != 0)) {
			snprintf(err, errlen, "--eeprom %s: expected %zu bytes", path, e->size);
			return -1;
		}
	} else if (errno != ENOENT) {
		snprintf(err, errlen, "--eeprom %s: %s", path, strerror(errno));
		return -1;
	}
	memcpy(ee->eeprom, e->saved, e->size);
	e->written = f != NULL;
	return 0;
}

int eeprom_file_sync(struct eeprom_file *e, avr_t *avr)
{
	if (!e->path[0])
		return 0;
	avr_eeprom_t *ee = sim_eeprom(avr);
	if (!ee)
		return -1;
	const uint8_t *now = ee->eeprom;
	if (e->written && memcmp(now, e->saved, e->size) == 0)
		return 0;
	if (file_write_atomic(e->path, (const char *)now, e->size) < 0)
		return -1;
	memcpy(e->saved, now, e->size);
	e->written = 1;
	return 0;
}
