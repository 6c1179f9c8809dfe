/* nprfx I/O (libnprfx-io) — the guard every reader calls before OpenImageIO touches a file (io_guard.cpp): the
 * EXR checks of io_validate.h, a size check of other formats, and the read deadline. */
#ifndef NPRFX_CLI_IO_GUARD_H
#define NPRFX_CLI_IO_GUARD_H

#include <stdbool.h>

#include "io_validate.h"
#include "nprfx/nprfx.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The guard every reader (io_read.h) calls first. EXR files (by their magic number) go through
 * internal_io_validate_exr; other formats have their header's size checked through OpenImageIO in
 * NPRFX_GUARD_READ mode. A file that cannot be opened passes: the reader reports that itself.
 * Also arms this thread's read deadline (internal_io_deadline_passed). */
nprfx_result internal_io_guard(nprfx_context *ctx, const char *path, int mode);

/* The read deadline of this thread, armed by internal_io_guard from NPRFX_READ_TIMEOUT: non-zero
 * once it has passed. internal_io_read_progress has OpenImageIO's ProgressCallback signature
 * (returns true to stop a read_image). */
int internal_io_deadline_passed(void);
bool internal_io_read_progress(void *user, float done);
/* The message for a read stopped by the deadline, naming the file. */
nprfx_result internal_io_deadline_error(nprfx_context *ctx, const char *path);

#ifdef __cplusplus
}
#endif
#endif
