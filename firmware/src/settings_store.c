/* EEPROM: every record is [data][checksum] (settings_checksum).
 *   0    settings version byte, then settings_t
 *   128  GC_SLOTS stored positions (G54..G59, G28, G30), X Y Z floats each (G54 only
 *        read and written without GRBL_WCS)
 *   256  $N0, $N1 and the $I= string, LINE_SIZE + 1 chars each (GRBL_LINES)
 * A bad copy reads as zeros or an empty line and is rewritten so, as GRBL does. */
#include <avr/eeprom.h>
#include <avr/wdt.h>
#include <string.h>
#include "gcode.h"
#include "settings.h"

#define EE_VERSION_ADDR ((uint8_t *)0)
#define EE_SETTINGS 1
#define EE_COORDS 128
#define COORD_BYTES (GC_AXES * sizeof(float))
#define EE_LINES 256
#define EE_LINE_BYTES (LINE_SIZE + 1)

static uint8_t ee_load(void *dst, uint16_t addr, uint8_t len)
{
    eeprom_read_block(dst, (const void *)addr, len);
    return eeprom_read_byte((const uint8_t *)(addr + len)) == settings_checksum(dst, len);
}

static void ee_save(const void *src, uint16_t addr, uint8_t len)
{
    wdt_reset(); /* ~3.4 ms a changed byte */
    eeprom_update_block(src, (void *)addr, len);
    eeprom_update_byte((uint8_t *)(addr + len), settings_checksum(src, len));
    wdt_reset();
}

uint8_t settings_load(void)
{
    settings_t tmp;
    if (ee_load(&tmp, EE_SETTINGS, sizeof(tmp)) && eeprom_read_byte(EE_VERSION_ADDR) == SETTINGS_VERSION) {
        settings = tmp;
        return 1;
    }
    settings_restore(RESTORE_ALL);
    return 0;
}

void settings_save(void)
{
    eeprom_update_byte(EE_VERSION_ADDR, SETTINGS_VERSION);
    ee_save(&settings, EE_SETTINGS, sizeof(settings));
}

uint8_t coord_load(uint8_t slot, float *xyz)
{
    uint16_t addr = EE_COORDS + slot * (COORD_BYTES + 1);
    if (ee_load(xyz, addr, COORD_BYTES))
        return 1;
    memset(xyz, 0, COORD_BYTES);
    ee_save(xyz, addr, COORD_BYTES);
    return 0;
}

void coord_save(uint8_t slot, const float *xyz) { ee_save(xyz, EE_COORDS + slot * (COORD_BYTES + 1), COORD_BYTES); }

#if GRBL_LINES
uint8_t eeline_load(uint8_t slot, char *line)
{
    uint16_t addr = EE_LINES + slot * (EE_LINE_BYTES + 1);
    if (ee_load(line, addr, EE_LINE_BYTES) && memchr(line, 0, EE_LINE_BYTES))
        return 1;
    line[0] = 0;
    eeline_save(slot, line);
    return 0;
}

void eeline_save(uint8_t slot, const char *line)
{
    char buf[EE_LINE_BYTES];
    strncpy(buf, line, EE_LINE_BYTES); /* zero-filled: the checksum covers a fixed size */
    buf[LINE_SIZE] = 0;
    ee_save(buf, EE_LINES + slot * (EE_LINE_BYTES + 1), EE_LINE_BYTES);
}
#endif

void settings_restore(uint8_t what)
{
    if (what & RESTORE_SETTINGS) {
        settings_defaults(&settings);
        settings_save();
    }
    if (what & RESTORE_COORDS) {
        static const float zero[GC_AXES];
        for (uint8_t i = 0; i < (GRBL_WCS ? GC_SLOTS : 1); i++) /* (the 328P stores G54 only) */
            coord_save(i, zero);
    }
#if GRBL_LINES
    if (what & RESTORE_LINES)
        for (uint8_t i = 0; i < EELINE_COUNT; i++)
            eeline_save(i, "");
#endif
}
