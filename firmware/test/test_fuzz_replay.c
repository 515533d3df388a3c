/* Replays the fuzz corpus and thousands of deterministic pseudo-random
 * inputs through the fuzz target; the sanitizers turn any memory error or
 * undefined behaviour into a failure. */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "tests.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define RANDOM_INPUTS 3000

static uint32_t rng = 12345;
static uint32_t next_rand(void)
{
    rng = rng * 1664525u + 1013904223u;
    return rng >> 8;
}

static const char *const tokens[] = {
    "G0", "G1", "G2", "G3", "G4", "G20", "G21", "G28", "G90", "G91", "G92", "G53", "M3", "M5",
    "M300", "M2", "M17", "M18", "X", "Y", "Z", "I", "J", "R", "F", "P", "S", "N", "$", "$J=", "=",
    "-", ".", "0", "1", "9", "10", "0.5", "-3.25", "1e5", "300", "99999", " ", "(", ")", ";", "\n",
    "\r\n", "\t", "\x00", "\xff", "?", "!", "~"};

static size_t random_input(uint8_t *buf, size_t cap)
{
    size_t n = 0;
    size_t len = next_rand() % cap;
    uint8_t mode = (uint8_t)(next_rand() % 3);
    while (n < len) {
        if (mode == 0) {
            buf[n++] = (uint8_t)next_rand();
        } else {
            const char *t = tokens[next_rand() % (sizeof(tokens) / sizeof(tokens[0]))];
            size_t tl = strlen(t);
            if (tl == 0)
                tl = 1; /* the NUL token */
            for (size_t i = 0; i < tl && n < len; i++)
                buf[n++] = (uint8_t)t[i];
            if (mode == 2 && next_rand() % 4 == 0 && n < len)
                buf[n++] = '\n';
        }
    }
    return n;
}

void test_fuzz_replay(void)
{
    size_t files = 0;
    DIR *d = opendir(fuzz_corpus_dir);
    CHECK(d != NULL);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d))) {
            if (e->d_name[0] == '.')
                continue;
            char path[512];
            snprintf(path, sizeof(path), "%s/%s", fuzz_corpus_dir, e->d_name);
            FILE *f = fopen(path, "rb");
            if (!f)
                continue;
            static uint8_t buf[1 << 16];
            size_t n = fread(buf, 1, sizeof(buf), f);
            fclose(f);
            LLVMFuzzerTestOneInput(buf, n);
            files++;
        }
        closedir(d);
    }
    CHECK(files >= 5);
    static uint8_t buf[2048];
    for (int i = 0; i < RANDOM_INPUTS; i++) {
        size_t n = random_input(buf, sizeof(buf));
        LLVMFuzzerTestOneInput(buf, n);
    }
    /* an endless line and a 40-digit number */
    static uint8_t endless[20000];
    memset(endless, 'G', sizeof(endless));
    LLVMFuzzerTestOneInput(endless, sizeof(endless));
}
