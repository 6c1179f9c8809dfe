/* nprfx CLI — what one image may cost before the runner refuses it (issue 15, damaged files).
 *
 * One bound on memory covers every image the runner makes in one piece: a plate read from a file,
 * a synth frame, a node's output frame. It is checked before anything is allocated, so a damaged
 * header that declares a 2000000000x3 window, or a graph asking for a 16384x16384 frame of 27
 * channels, is refused with the size and the limit instead of failing after gigabytes. A second
 * bound on time stops one file's read (docs/design.md §4, "Damaged files").
 *
 *   NPRFX_READ_LIMIT    bytes one image may take: "4G", "512M", "1073741824"; "0": no limit.
 *                       Default: 4 GiB, or half the physical memory when that is less.
 *   NPRFX_READ_TIMEOUT  seconds one file's read may take (a decimal number; "0": no limit).
 *                       Default: 60. */
#ifndef NPRFX_CLI_IO_LIMITS_H
#define NPRFX_CLI_IO_LIMITS_H

#include <stddef.h>
#include <stdint.h>

#include "nprfx/nprfx.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The memory bound in bytes (UINT64_MAX: none). A malformed NPRFX_READ_LIMIT is an error. */
nprfx_result nprfx_image_limit(nprfx_context *ctx, uint64_t *bytes);

/* The read time bound in seconds (0: none). A malformed NPRFX_READ_TIMEOUT is an error. */
nprfx_result nprfx_read_timeout(nprfx_context *ctx, double *seconds);

/* Monotonic clock in seconds. */
double nprfx_limits_now(void);

/* "44.7 GiB", "512 MiB", "900 bytes": sizes in messages. */
void nprfx_format_bytes(char *buf, size_t n, uint64_t bytes);

/* Refuse an image of w x h pixels and `channels` float channels (plus extra_bytes of scratch)
 * when it would exceed the memory bound: "WHAT WxH with N channels needs 27.0 GiB, above the
 * 4 GiB image memory limit (NPRFX_READ_LIMIT)". what names the file, node or option and what the
 * size is ("'a.exr': data window", "synth --size"). */
nprfx_result nprfx_image_limit_check(nprfx_context *ctx, const char *what, int64_t w, int64_t h,
                                     int64_t channels, uint64_t extra_bytes);

#ifdef __cplusplus
}
#endif
#endif
