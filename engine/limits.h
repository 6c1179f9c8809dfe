/* nprfx CLI — the memory limit and the read time bound.
 *
 * One memory limit covers the images the runner holds: every image it makes in one piece (a plate
 * read from a file, a synth frame, a node's output frame) is checked against it before anything
 * is allocated, so a damaged header that declares a 2000000000x3 window, or a graph asking for a
 * 16384x16384 frame of 27 channels, is refused with the size and the limit instead of failing
 * after gigabytes; and a graph's frames together are held under it (the plan's estimate before
 * the first frame, each allocation during the render: graph_estimate.c, graph_memory.c). A second
 * bound on time stops one file's read (docs/design.md §4, "Damaged files").
 *
 *   --mem-limit SIZE    (run, bench, bench-graph) the limit; overrides NPRFX_READ_LIMIT.
 *   NPRFX_READ_LIMIT    the same limit from the environment (named when it bounded reads only):
 *                       "4G", "512M", "1073741824"; "0": no limit.
 *                       Default: half the physical memory.
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
/* Set the limit for the rest of the process (--mem-limit; UINT64_MAX: none), over the
 * environment's. */
void cli_mem_limit_set(uint64_t bytes);
/* Where the limit comes from, for messages: "--mem-limit", "NPRFX_READ_LIMIT" or the default. */
const char *cli_mem_limit_origin(void);
/* Parse a size: "4G", "512M", "1.5GiB", "1073741824"; "0" is no limit (UINT64_MAX).
 * NPRFX_ERR_INVALID_ARGUMENT (nothing raised) when text is not one. */
nprfx_result nprfx_parse_size(const char *text, uint64_t *bytes);

/* The read time bound in seconds (0: none). A malformed NPRFX_READ_TIMEOUT is an error. */
nprfx_result internal_io_read_timeout(nprfx_context *ctx, double *seconds);

/* "44.7 GiB", "512 MiB", "900 bytes": sizes in messages. */
void nprfx_format_bytes(char *buf, size_t n, uint64_t bytes);

/* Refuse an image of w x h pixels and `channels` float channels (plus extra_bytes of scratch)
 * when it would exceed the memory bound: "WHAT WxH with N channels needs 27.0 GiB, above the
 * 4 GiB memory limit (NPRFX_READ_LIMIT)". what names the file, node or option and what the
 * size is ("'a.exr': data window", "synth --size"). */
nprfx_result nprfx_image_limit_check(nprfx_context *ctx, const char *what, int64_t w, int64_t h,
                                     int64_t channels, uint64_t extra_bytes);

#ifdef __cplusplus
}
#endif
#endif
