/* Minimal test harness: CHECK records a failure and carries on. */
#ifndef CHECK_H
#define CHECK_H
#include <stdio.h>

extern int checks_failed_in_test;
#define CHECK(cond)                                                              \
    do {                                                                         \
        if (!(cond)) {                                                           \
            printf("  FAIL %s:%d: %s\n", __FILE__, __LINE__, #cond);             \
            checks_failed_in_test++;                                             \
        }                                                                        \
    } while (0)
#define CHECK_NEAR(a, b, tol) CHECK(fabs((double)(a) - (double)(b)) <= (tol))

typedef void (*test_fn)(void);
typedef struct {
    const char *name;
    test_fn fn;
} test_case;
#endif
