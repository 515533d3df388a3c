/* EEPROM persistence: the image is loaded at start (blank 0xFF if the file is
 * missing), compared with the last saved copy now and then, and saved
 * atomically (tmp + rename) when it changed and at exit. */
#ifndef EEPROM_FILE_H
#define EEPROM_FILE_H

#include <stddef.h>
#include <stdint.h>

#include "sim_avr.h"

#define EEPROM_MAX 4096

struct eeprom_file {
	char path[512];          /* empty: no persistence */
	size_t size;
	int written;             /* the file holds saved[] */
	uint8_t saved[EEPROM_MAX];
};

int eeprom_file_load(struct eeprom_file *e, avr_t *avr, const char *path, char *err, size_t errlen);
/* saves when the simulated EEPROM differs from the last save; -1 on error */
int eeprom_file_sync(struct eeprom_file *e, avr_t *avr);

#endif
