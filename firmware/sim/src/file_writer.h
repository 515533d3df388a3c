/* A file rewritten whole, off the simulation thread: the loop hands over the
 * new content and goes on; a thread of its own writes it (tmp + rename, so
 * readers never see half a file). A rename on a busy disk took 0.2 s under a
 * loaded test run, and the loop stops serving the pty meanwhile: the server
 * would count the board silent. Content handed over while a write is under
 * way replaces any still waiting: the latest wins. */
#ifndef FILE_WRITER_H
#define FILE_WRITER_H

#include <pthread.h>
#include <stddef.h>

struct file_writer {
	char path[1024];
	pthread_t thread;
	pthread_mutex_t lock;
	pthread_cond_t wake;
	char *pending;   /* content waiting to be written (malloc'd), or NULL */
	size_t pending_len;
	int stopping;
	int started;
};

/* 0, or -1 when the thread cannot start (then writes happen in the caller) */
int file_writer_start(struct file_writer *w, const char *path);
/* takes `content` (malloc'd, `len` bytes) and frees it once written */
void file_writer_put(struct file_writer *w, char *content, size_t len);
/* writes what is waiting, then ends the thread */
void file_writer_stop(struct file_writer *w);

/* writes `len` bytes to `path` through `path.PID.tmp` and a rename; 0 or -1 */
int file_write_atomic(const char *path, const char *content, size_t len);

#endif
