/* nprfx I/O (libnprfx-io) — checks a file before OpenImageIO touches it (damaged files).
 *
 * OpenImageIO trusts a header: a damaged EXR that declares a 2000000000x3 window, a chunk table
 * larger than the file or chunks that inflate a thousandfold makes it allocate gigabytes, rebuild
 * offset tables for seconds, or return garbage channel names as if the read had worked. The guard
 * parses the header on its own (OpenEXRCore, which reports instead of printing), walks every chunk
 * header against the file's size, and estimates what the read will allocate, so such a file is
 * refused up front with a message naming the file and what is wrong (docs/design.md §4). */
#ifndef NPRFX_CLI_IO_VALIDATE_H
#define NPRFX_CLI_IO_VALIDATE_H

#include "nprfx/nprfx.h"

#ifdef __cplusplus
extern "C" {
#endif

/* How far the checks go (io_guard.h's internal_io_guard takes the same modes). */
typedef enum nprfx_io_guard_mode {
    /* Header facts only (nprfx info, attributes): structure and names, no memory bound. */
    NPRFX_GUARD_HEADER = 0,
    /* A full read: also the decoded size against the memory bound (NPRFX_READ_LIMIT). */
    NPRFX_GUARD_READ = 1,
    /* A read of channels the caller chooses: as NPRFX_GUARD_READ, but the decoded size is held
     * to the memory bound by the reader, once it knows the channels it delivers. */
    NPRFX_GUARD_READ_CHOSEN = 2
} nprfx_io_guard_mode;

/* The EXR checks: header parse, parts, windows, channel names and count, tile sizes, chunk
 * counts and every chunk's place against the file's size and a plausible compression ratio, and
 * in NPRFX_GUARD_READ mode the decoded size. deadline: engine_now() time after which the
 * walk over the chunks gives up (0: none). */
nprfx_result internal_io_validate_exr(nprfx_context *ctx, const char *path, int mode,
                                      double deadline);

/* Why part `part` of the file the last internal_io_validate_exr on this thread checked is
 * broken, or NULL when it is whole. A part whose chunks are missing or damaged while its header
 * is whole (a render killed before it wrote its later parts) does not fail the check when
 * another part is whole: the reader leaves it out with a warning and refuses a read that asks
 * for it. internal_io_broken_reset forgets them (the guard, before any file). */
const char *internal_io_broken_part(int part);
void internal_io_broken_reset(void);

/* 1 when the file begins with the EXR magic number. */
int internal_io_is_exr(const char *path);

#ifdef __cplusplus
}
#endif
#endif
