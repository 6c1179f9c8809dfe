/* nprfx — the parallel-for executor interface.
 *
 * Nodes never create threads: they split work into index ranges and hand them to the executor the
 * caller supplies (the CLI a pthread pool, the OFX adapter the host's multithread suite). Each
 * range writes disjoint output, so results are bit-identical for any thread count. */
#ifndef NPRFX_EXEC_H
#define NPRFX_EXEC_H

#include "nprfx/result.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Process items [begin, end). `worker` is in [0, num_workers) and unique among the chunks of one
 * parallel_for call running at the same time, so it may index scratch memory allocated for that
 * call; it is not unique across calls (nested or inline calls report 0), so do not keep
 * per-worker scratch between calls. */
typedef void (*nprfx_range_fn)(void *user, int begin, int end, int worker);

typedef struct nprfx_executor {
    size_t size; /* sizeof(nprfx_executor) */
    void *impl;
    int (*num_workers)(void *impl);
    /* Run fn over [0, count) in chunks of about `grain` items; returns when all are done. */
    void (*parallel_for)(void *impl, int count, int grain, nprfx_range_fn fn, void *user);
} nprfx_executor;

/* Convenience: ex may be NULL (serial). */
NPRFX_API void nprfx_parallel_for(const nprfx_executor *ex, int count, int grain, nprfx_range_fn fn,
                                  void *user);
NPRFX_API int nprfx_executor_workers(const nprfx_executor *ex);

/* A pthread pool. threads <= 0 means the number of online CPUs. */
typedef struct nprfx_pool nprfx_pool;
NPRFX_API nprfx_result nprfx_pool_create(int threads, nprfx_pool **out);
NPRFX_API void nprfx_pool_destroy(nprfx_pool *pool);
NPRFX_API const nprfx_executor *nprfx_pool_executor(nprfx_pool *pool);

#ifdef __cplusplus
}
#endif
#endif
