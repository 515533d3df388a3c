/* Stored positions for the host builds (unit tests, fuzzer): RAM instead
 * of EEPROM, all valid and zero at start; host_store_corrupt() makes one
 * slot read as a bad copy once (GRBL's error:7 path). */
#include <string.h>
#include "gcode.h"
#include "host_store.h"

static float slots[GC_SLOTS][GC_AXES];
static uint8_t bad;

void host_store_reset(void)
{
    memset(slots, 0, sizeof(slots));
    bad = 0;
}

void host_store_corrupt(uint8_t slot) { bad |= (uint8_t)(1u << slot); }

uint8_t coord_load(uint8_t slot, float *xyz)
{
    if (bad & (1u << slot)) {
        bad &= (uint8_t)~(1u << slot);
        memset(slots[slot], 0, sizeof(slots[slot]));
        memset(xyz, 0, sizeof(slots[slot]));
        return 0;
    }
    memcpy(xyz, slots[slot], sizeof(slots[slot]));
    return 1;
}

void coord_save(uint8_t slot, const float *xyz) { memcpy(slots[slot], xyz, sizeof(slots[slot])); }
