#include "control.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/un.h>
#include <unistd.h>

int control_open(struct control *c, const char *path, char *err, size_t errlen)
{
	memset(c, 0, sizeof *c);
	c->listen_fd = -1;
	for (int i = 0; i < CONTROL_MAX_CLIENTS; i++)
		c->client[i].fd = -1;
	if (!path || !*path)
		return 0;
	if (strlen(path) >= sizeof c->path) {
		/* the path's start only: with all of it, a 32-bit gcc sees an output that may
		 * pass INT_MAX (-Werror=format-truncation) */
		snprintf(err, errlen, "--control %.64s...: path longer than %zu bytes", path,
			 sizeof c->path - 1);
		return -1;
	}
	snprintf(c->path, sizeof c->path, "%s", path);
	int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
	struct sockaddr_un addr = { .sun_family = AF_UNIX };
	memcpy(addr.sun_path, c->path, strlen(c->path) + 1);
	unlink(c->path);
	if (fd < 0 || bind(fd, (struct sockaddr *)&addr, sizeof addr) < 0 || listen(fd, 8) < 0) {
		snprintf(err, errlen, "--control %s: %s", path, strerror(errno));
		if (fd >= 0)
			close(fd);
		c->path[0] = 0;
		return -1;
	}
	c->listen_fd = fd;
	return 0;
}

int control_pollfds(const struct control *c, struct pollfd *fds, int max)
{
	int n = 0;
	if (c->listen_fd >= 0 && n < max)
		fds[n++] = (struct pollfd){ .fd = c->listen_fd, .events = POLLIN };
	for (int i = 0; i < CONTROL_MAX_CLIENTS && n < max; i++)
		if (c->client[i].fd >= 0)
			fds[n++] = (struct pollfd){ .fd = c->client[i].fd, .events = POLLIN };
	return n;
}

static void drop(struct control_client *cl)
{
	close(cl->fd);
	cl->fd = -1;
	cl->len = 0;
}

/* Answers can be large (the trace): send them whole, blocking up to 2 s. */
static void send_all(struct control_client *cl, const char *data, size_t len)
{
	int flags = fcntl(cl->fd, F_GETFL);
	fcntl(cl->fd, F_SETFL, flags & ~O_NONBLOCK);
	struct timeval tv = { .tv_sec = 2 };
	setsockopt(cl->fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
	while (len) {
		ssize_t n = send(cl->fd, data, len, MSG_NOSIGNAL);
		if (n <= 0) {
			drop(cl);
			return;
		}
		data += n;
		len -= (size_t)n;
	}
	fcntl(cl->fd, F_SETFL, flags);
}

static void run_line(struct control_client *cl, char *line, control_handler handler, void *ctx)
{
	size_t n = strlen(line);
	if (n && line[n - 1] == '\r')
		line[n - 1] = 0;
	char *out = NULL;
	size_t outlen = 0;
	FILE *reply = open_memstream(&out, &outlen);
	if (!reply)
		return;
	handler(ctx, line, reply);
	fclose(reply);
	send_all(cl, out, outlen);
	free(out);
}

static void service_client(struct control_client *cl, control_handler handler, void *ctx)
{
	for (;;) {
		ssize_t n = read(cl->fd, cl->buf + cl->len, sizeof cl->buf - 1 - cl->len);
		if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) {
			drop(cl);
			return;
		}
		if (n < 0)
			return;
		cl->len += (size_t)n;
		char *start = cl->buf, *nl;
		while (cl->fd >= 0 && (nl = memchr(start, '\n', cl->len - (size_t)(start - cl->buf)))) {
			*nl = 0;
			if (cl->skipping)
				cl->skipping = 0; /* the end of the over-long line */
			else
				run_line(cl, start, handler, ctx);
			start = nl + 1;
		}
		if (cl->fd < 0)
			return;
		cl->len -= (size_t)(start - cl->buf);
		memmove(cl->buf, start, cl->len);
		if (cl->len == sizeof cl->buf - 1) {
			/* answer once, then ignore the line up to its newline */
			if (!cl->skipping) {
				static const char msg[] = "error: line too long\n";
				send_all(cl, msg, sizeof msg - 1);
				if (cl->fd < 0)
					return;
			}
			cl->skipping = 1;
			cl->len = 0;
		}
	}
}

void control_service(struct control *c, control_handler handler, void *ctx)
{
	if (c->listen_fd < 0)
		return;
	for (;;) {
		int fd = accept4(c->listen_fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
		if (fd < 0)
			break;
		int slot = -1;
		for (int i = 0; i < CONTROL_MAX_CLIENTS && slot < 0; i++)
			if (c->client[i].fd < 0)
				slot = i;
		if (slot < 0) {
			static const char msg[] = "error: too many control connections\n";
			send(fd, msg, sizeof msg - 1, MSG_NOSIGNAL);
			close(fd);
			continue;
		}
		c->client[slot].fd = fd;
		c->client[slot].len = 0;
		c->client[slot].skipping = 0;
	}
	for (int i = 0; i < CONTROL_MAX_CLIENTS; i++)
		if (c->client[i].fd >= 0)
			service_client(&c->client[i], handler, ctx);
}

void control_close(struct control *c)
{
	for (int i = 0; i < CONTROL_MAX_CLIENTS; i++)
		if (c->client[i].fd >= 0)
			drop(&c->client[i]);
	if (c->listen_fd >= 0) {
		close(c->listen_fd);
		unlink(c->path);
	}
	c->listen_fd = -1;
}
