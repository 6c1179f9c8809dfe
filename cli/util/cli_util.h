/* nprfx CLI — small shared helpers: the context every command runs with, thread count. */
#ifndef NPRFX_CLI_UTIL_H
#define NPRFX_CLI_UTIL_H

#include <stdio.h>

#include "nprfx/nprfx.h"

/* Threads from --threads (when > 0), else $NPRFX_THREADS, else all cores. */
int nprfx_cli_threads(int requested);

/* The data directory (the stipple node's ivs.bin): $NPRFX_DATA_DIR when set (empty: none), else
 * share/nprfx beside the executable (the build tree) or ../share/nprfx (an install), the first
 * holding ivs.bin; NULL when there is none (the data is then generated when needed). */
const char *nprfx_cli_data_dir(char *buf, size_t size);

/* A context whose executor is a pthread pool of `threads` threads, and the data directory. Errors
 * are not printed as they are raised: layers add what they know through scoped contexts, and
 * commands print the finished message once (nprfx_cli_message). */
typedef struct nprfx_cli_env {
    nprfx_context *ctx;
    nprfx_pool *pool;
} nprfx_cli_env;
int nprfx_cli_env_init(nprfx_cli_env *env, int threads);
void nprfx_cli_env_free(nprfx_cli_env *env);

/* The last message raised through ctx, copied (valid until the next call from this thread). */
const char *nprfx_cli_message(const nprfx_context *ctx);

/* Monotonic clock in seconds. */
double nprfx_cli_now(void);

/* Peak resident memory of this process in MiB. */
double nprfx_cli_peak_mib(void);
/* The bytes per second a parallel memcpy of `bytes` (at least 64 MiB) moves, read plus
 * written, on the executor's threads: best of five (cli/bench_floor.c). 0 when out of memory. */
/* What nprfx bench and bench-graph both take (cli/bench_options.c). */
#define NPRFX_CLI_BENCH_MAX_SETS 64
typedef struct nprfx_cli_bench_options {
    const char *size, *scene, *mem_limit;
    const char *sets[NPRFX_CLI_BENCH_MAX_SETS];
    int nsets, frames, threads, no_pool;
} nprfx_cli_bench_options;
/* Consume argv[*i] (and its value) when it is one of the shared options: --size, --frames,
 * --threads, --scene, --set, --mem-limit, --no-pool. 1 when taken. */
int nprfx_cli_bench_option(int argc, char **argv, int *i, nprfx_cli_bench_options *o);
/* Parse o->size into w, h; 2 (with the message) when it is not WxH within 65536. */
int nprfx_cli_bench_size(const char *cmd, const nprfx_cli_bench_options *o, int *w, int *h);
/* The copy speed this machine reaches on ex's threads, bytes/s read and written (bench's floor). */
double nprfx_cli_copy_bandwidth(const nprfx_executor *ex, size_t bytes);
/* Copy src to dst (src NULL: zero dst), `bytes` cut into `parts` spread over ex's threads. */
void nprfx_cli_parallel_bytes(const nprfx_executor *ex, void *dst, const void *src, size_t bytes,
                              int parts);

/* --mem-limit SIZE of command `cmd`: set the process's memory limit (io_limits.h), or say why
 * SIZE is not a size on stderr and return non-zero. */
int nprfx_cli_set_mem_limit(const char *prog, const char *cmd, const char *size);

struct nprfx_graph;
struct nprfx_graph_plan_info;
/* The --stats table of a graph after `frames` frames: per node its calls, ms per frame and
 * bytes allocated per frame, then the graph's peak of frames held, the plan's estimate and the
 * process's peak resident size. */
void nprfx_cli_print_stats(FILE *f, struct nprfx_graph *g, int frames,
                           const struct nprfx_graph_plan_info *plan);

#endif
