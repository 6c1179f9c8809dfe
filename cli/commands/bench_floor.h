/* nprfx CLI — bench's memory floor: the copy speed this machine reaches. */
#ifndef NPRFX_CLI_BENCH_FLOOR_H
#define NPRFX_CLI_BENCH_FLOOR_H

#include <stddef.h>

#include "nprfx/nprfx.h"

/* The bytes per second a parallel memcpy of `bytes` (at least 64 MiB) moves, read plus written,
 * on ex's threads: best of five. 0 when out of memory. */
double cli_copy_bandwidth(const nprfx_executor *ex, size_t bytes);

#endif
