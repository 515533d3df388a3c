/* The main loop: lines from the serial port to the parser or $ commands,
 * one acknowledgement per line; soft reset. */
#ifndef PROTOCOL_H
#define PROTOCOL_H
#include <stdint.h>
void protocol_run(void);
uint8_t protocol_gcode(const char *line); /* one G-code line through the parser and the machine */
void protocol_startup_lines(void);       /* $N0, $N1 with their ">line:ok" echo (GRBL_LINES) */
#endif
