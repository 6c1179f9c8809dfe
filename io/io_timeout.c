/* nprfx I/O — io_timeout.h: NPRFX_READ_TIMEOUT and the clock deadlines are in. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "io_timeout.h"

#include <math.h>
#include <stdlib.h>
#include <time.h>

nprfx_result internal_io_read_timeout(nprfx_context *ctx, double *seconds)
{
    const char *e = getenv("NPRFX_READ_TIMEOUT");
    *seconds = 60.0;
    if (!e || !*e) return NPRFX_OK;
    char *end = NULL;
    double v = strtod(e, &end);
    if (end == e || *end || !(v >= 0) || !isfinite(v))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "NPRFX_READ_TIMEOUT='%s' is not a number of seconds (0 for none)", e);
    *seconds = v;
    return NPRFX_OK;
}

double internal_io_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
