/* The main loop: lines from the serial port to the parser or $ commands,
 * one acknowledgement per line; soft reset. */
#ifndef PROTOCOL_H
#define PROTOCOL_H
void protocol_run(void);
#endif
