/* Minimal test harness: CHECK-style macros that count, print the failing expression with its
 * file and line, and a closing "N passed, N failed" line. A test file's main returns
 * check_finish(). */
#ifndef NPRFX_TEST_CHECK_H
#define NPRFX_TEST_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/context.h"

static int check_passed, check_failed;

#define CHECK(cond)                                                                              \
    do {                                                                                         \
        if (cond) {                                                                              \
            check_passed++;                                                                      \
        } else {                                                                                 \
            check_failed++;                                                                      \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond);            \
        }                                                                                        \
    } while (0)

/* |a - b| <= tol, printing both values on failure. */
#define CHECK_NEAR(a, b, tol)                                                                    \
    do {                                                                                         \
        double check_a_ = (double)(a), check_b_ = (double)(b), check_t_ = (double)(tol);        \
        if (fabs(check_a_ - check_b_) <= check_t_) {                                             \
            check_passed++;                                                                      \
        } else {                                                                                 \
            check_failed++;                                                                      \
            fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.9g, %s = %.9g, tol %.3g\n",        \
                    __FILE__, __LINE__, #a, check_a_, #b, check_b_, check_t_);                   \
        }                                                                                        \
    } while (0)

#define CHECK_OK(expr)                                                                           \
    do {                                                                                         \
        int check_r_ = (expr);                                                                   \
        if (check_r_ == 0) {                                                                     \
            check_passed++;                                                                      \
        } else {                                                                                 \
            check_failed++;                                                                      \
            fprintf(stderr, "%s:%d: %s returned %d\n", __FILE__, __LINE__, #expr, check_r_);     \
        }                                                                                        \
    } while (0)

static inline int check_finish(void)
{
    printf("%d passed, %d failed\n", check_passed, check_failed);
    return check_failed ? 1 : 0;
}

/* The last message raised on ctx, copied (valid until the next call; tests are one thread). */
static inline const char *th_error(const nprfx_context *ctx)
{
    static char buf[2048];
    nprfx_context_last_error(ctx, buf, sizeof buf);
    return buf;
}

#endif
