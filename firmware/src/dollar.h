/* $ system commands: $$ $N=v $X $H $J= $C $I $G $# $ (help). */
#ifndef DOLLAR_H
#define DOLLAR_H
#include <stdint.h>
uint8_t dollar_execute(const char *line); /* line starts with '$' */
#endif
