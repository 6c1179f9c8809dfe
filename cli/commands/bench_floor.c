/* The memory floor bench reports beside a node's time: the bytes of frames a render cannot
 * avoid moving (its inputs read once, its output written once; the runner counts them), at the
 * copy bandwidth this machine reaches with the same threads. A node near its floor is limited
 * by memory, not by its arithmetic: blend, threshold-map and warp should be. */
#include <stdlib.h>
#include <string.h>

#include "engine/engine_util.h"
#include "bench_floor.h"
#include "util/cli_util.h"

double cli_copy_bandwidth(const nprfx_executor *ex, size_t bytes)
{
    if (bytes < ((size_t)64 << 20)) bytes = (size_t)64 << 20; /* well past the caches */
    unsigned char *src = malloc(bytes), *dst = malloc(bytes);
    if (!src || !dst) {
        free(src);
        free(dst);
        return 0;
    }
    memset(src, 1, bytes); /* fault both in: the floor is about traffic, not page faults */
    memset(dst, 2, bytes);
    double best = 1e30;
    for (int rep = 0; rep < 5; rep++) {
        double t0 = engine_now();
        engine_parallel_bytes(ex, dst, src, bytes, 64);
        double t = engine_now() - t0;
        if (t < best) best = t;
    }
    free(src);
    free(dst);
    return best > 0 ? 2.0 * (double)bytes / best : 0; /* read and written */
}
