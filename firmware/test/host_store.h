#ifndef HOST_STORE_H
#define HOST_STORE_H
#include <stdint.h>
void host_store_reset(void);
void host_store_corrupt(uint8_t slot);
#endif
