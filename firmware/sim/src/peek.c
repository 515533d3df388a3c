#include <stdlib.h>
#include "peek.h"

void peek_reply(avr_t *avr, const char *arg, FILE *reply)
{
	char *end;
	unsigned long addr = strtoul(arg, &end, 0) & 0xffffUL; /* ELF: 0x800000 + data address */
	unsigned long len = strtoul(end, &end, 0);
	if (!len || len > 4096 || addr + len > (unsigned long)avr->ramend + 1) {
		fputs("error: peek ADDR LEN: LEN 1..4096 inside the data memory\n", reply);
		return;
	}
	for (unsigned long i = 0; i < len; i++)
		fprintf(reply, "%02x", avr->data[addr + i]);
	fputc('\n', reply);
}
