/* Settings in EEPROM: [version][settings_t][checksum] at address 0. */
#include <avr/eeprom.h>
#include <avr/wdt.h>
#include "settings.h"

#define EE_VERSION_ADDR ((uint8_t *)0)
#define EE_DATA_ADDR ((void *)1)
#define EE_SUM_ADDR ((uint8_t *)(1 + sizeof(settings_t)))

uint8_t settings_load(void)
{
    settings_t tmp;
    eeprom_read_block(&tmp, EE_DATA_ADDR, sizeof(tmp));
    if (eeprom_read_byte(EE_VERSION_ADDR) == SETTINGS_VERSION &&
        eeprom_read_byte(EE_SUM_ADDR) == settings_checksum((const uint8_t *)&tmp, sizeof(tmp))) {
        settings = tmp;
        return 1;
    }
    settings_defaults(&settings);
    settings_save();
    return 0;
}

void settings_save(void)
{
    wdt_reset();
    eeprom_update_byte(EE_VERSION_ADDR, SETTINGS_VERSION);
    eeprom_update_block(&settings, EE_DATA_ADDR, sizeof(settings));
    eeprom_update_byte(EE_SUM_ADDR, settings_checksum((const uint8_t *)&settings, sizeof(settings)));
    wdt_reset();
}
