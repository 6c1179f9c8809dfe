/* nprfx I/O — the bound on one file's read time (docs/design.md §4, "Damaged files"):
 *   NPRFX_READ_TIMEOUT  seconds one file's read may take (a decimal number; "0": no limit).
 *                       Default: 60. */
#ifndef NPRFX_IO_TIMEOUT_H
#define NPRFX_IO_TIMEOUT_H

#include "nprfx/context.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The read time bound in seconds (0: none). A malformed NPRFX_READ_TIMEOUT is an error. */
nprfx_result internal_io_read_timeout(nprfx_context *ctx, double *seconds);
/* The monotonic clock deadlines are in, seconds. libnprfx-io's own: the engine's clock
 * (engine/engine_util.h) is private to libnprfx. */
double internal_io_now(void);

#ifdef __cplusplus
}
#endif
#endif
