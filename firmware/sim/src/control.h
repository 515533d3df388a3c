/* The control socket: a Unix stream socket, one command a line, one answer
 * line each. Serviced from the simulation loop (non-blocking), so commands
 * take effect between instructions, in the simulation thread. */
#ifndef CONTROL_H
#define CONTROL_H

#include <poll.h>
#include <stddef.h>
#include <stdio.h>

#define CONTROL_MAX_CLIENTS 8
#define CONTROL_LINE_MAX 1024

struct control_client {
	int fd;
	char buf[CONTROL_LINE_MAX];
	size_t len;
	int skipping;            /* dropping the rest of an over-long line */
};

struct control {
	int listen_fd;
	char path[108];          /* sun_path size */
	struct control_client client[CONTROL_MAX_CLIENTS];
};

/* handler writes the whole answer (one line, '\n' terminated) to reply */
typedef void (*control_handler)(void *ctx, const char *line, FILE *reply);

int control_open(struct control *c, const char *path, char *err, size_t errlen);
/* fds to wake the loop on; returns how many were stored */
int control_pollfds(const struct control *c, struct pollfd *fds, int max);
void control_service(struct control *c, control_handler handler, void *ctx);
void control_close(struct control *c);

#endif
