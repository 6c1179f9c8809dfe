/* The memory floor bench reports beside a node's time: the bytes of frames a render cannot
 * avoid moving (its inputs read once, its output written once; the runner counts them), at the
 * copy bandwidth this machine reaches with the same threads. A node near its floor is limited
 * by memory, not by its arithmetic: blend, threshold-map and warp should be. */
#include <stdlib.h>
#include <string.h>

#include "util/cli_util.h"
#include "graph/graph.h"
#include "graph/internal_graph.h"

typedef struct bytes_job {
    const unsigned char *src; /* NULL: zero */
    unsigned char *dst;
    size_t bytes;
    int parts;
} bytes_job;

static void bytes_parts(void *user, int begin, int end, int worker)
{
    (void)worker;
    const bytes_job *j = user;
    for (int p = begin; p < end; p++) {
        size_t a = j->bytes * (size_t)p / (size_t)j->parts;
        size_t b = j->bytes * (size_t)(p + 1) / (size_t)j->parts;
        if (j->src)
            memcpy(j->dst + a, j->src + a, b - a);
        else
            memset(j->dst + a, 0, b - a);
    }
}

void nprfx_cli_parallel_bytes(const nprfx_executor *ex, void *dst, const void *src, size_t bytes,
                              int parts)
{
    bytes_job j = {src, dst, bytes, parts > 0 ? parts : 1};
    if (j.parts == 1 || !ex) {
        bytes_parts(&j, 0, j.parts, 0);
        return;
    }
    nprfx_parallel_for(ex, j.parts, 1, bytes_parts, &j);
}

double nprfx_cli_copy_bandwidth(const nprfx_executor *ex, size_t bytes)
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
        double t0 = internal_graph_now();
        nprfx_cli_parallel_bytes(ex, dst, src, bytes, 64);
        double t = internal_graph_now() - t0;
        if (t < best) best = t;
    }
    free(src);
    free(dst);
    return best > 0 ? 2.0 * (double)bytes / best : 0; /* read and written */
}
