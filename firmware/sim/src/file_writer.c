#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "file_writer.h"

int file_write_atomic(const char *path, const char *content, size_t len)
{
	char tmp[1100];
	snprintf(tmp, sizeof tmp, "%s.%d.tmp", path, (int)getpid());
	FILE *f = fopen(tmp, "w");
	if (!f)
		return -1;
	int ok = fwrite(content, 1, len, f) == len;
	ok = (fclose(f) == 0) && ok;
	if (!ok || rename(tmp, path) < 0) {
		int saved = errno;
		unlink(tmp);
		errno = saved;
		return -1;
	}
	return 0;
}

static void write_or_say(const char *path, const char *content, size_t len)
{
	if (file_write_atomic(path, content, len) < 0)
		fprintf(stderr, "plotsim: cannot write %s: %s\n", path, strerror(errno));
}

static void *run(void *arg)
{
	struct file_writer *w = arg;
	/* SIGTERM and the like go to the loop's thread (they end its ppoll), never
	 * here, where they would interrupt a write */
	sigset_t all;
	sigfillset(&all);
	pthread_sigmask(SIG_BLOCK, &all, NULL);
	pthread_mutex_lock(&w->lock);
	for (;;) {
		while (!w->pending && !w->stopping)
			pthread_cond_wait(&w->wake, &w->lock);
		if (!w->pending)
			break; /* stopping, nothing left */
		char *content = w->pending;
		size_t len = w->pending_len;
		w->pending = NULL;
		pthread_mutex_unlock(&w->lock);
		write_or_say(w->path, content, len);
		free(content);
		pthread_mutex_lock(&w->lock);
	}
	pthread_mutex_unlock(&w->lock);
	return NULL;
}

int file_writer_start(struct file_writer *w, const char *path)
{
	memset(w, 0, sizeof *w);
	snprintf(w->path, sizeof w->path, "%s", path);
	pthread_mutex_init(&w->lock, NULL);
	pthread_cond_init(&w->wake, NULL);
	if (pthread_create(&w->thread, NULL, run, w) != 0)
		return -1;
	w->started = 1;
	return 0;
}

void file_writer_put(struct file_writer *w, char *content, size_t len)
{
	if (!w->started) {
		write_or_say(w->path, content, len);
		free(content);
		return;
	}
	pthread_mutex_lock(&w->lock);
	free(w->pending); /* superseded before it was written */
	w->pending = content;
	w->pending_len = len;
	pthread_cond_signal(&w->wake);
	pthread_mutex_unlock(&w->lock);
}

void file_writer_stop(struct file_writer *w)
{
	if (!w->started)
		return;
	pthread_mutex_lock(&w->lock);
	w->stopping = 1;
	pthread_cond_signal(&w->wake);
	pthread_mutex_unlock(&w->lock);
	pthread_join(w->thread, NULL);
	w->started = 0;
}
