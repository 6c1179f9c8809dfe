/* nprfx CLI — the runner's lowest layer: the context every command runs with, the clocks,
 * strdup, peak memory and a parallel byte copy. */
#ifndef NPRFX_CLI_UTIL_H
#define NPRFX_CLI_UTIL_H

#include <stddef.h>

#include "nprfx/nprfx.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A context whose executor is a pthread pool of `threads` threads (when > 0, else
 * $NPRFX_THREADS, else all cores), and the data directory (the stipple node's ivs.bin). Errors
 * are not printed as they are raised: layers add what they know through scoped contexts, and
 * commands print the finished message once (cli_message). */
typedef struct cli_env {
    nprfx_context *ctx;
    nprfx_pool *pool;
} cli_env;
int cli_env_init(cli_env *env, int threads);
void cli_env_free(cli_env *env);

/* The last message raised through ctx, copied (valid until the next call from this thread). */
const char *cli_message(const nprfx_context *ctx);

/* Monotonic clock in seconds. */
double cli_now(void);
/* The process's CPU time in seconds, all threads (CLOCK_PROCESS_CPUTIME_ID). */
double cli_cpu_now(void);

/* A malloc'd copy of s (NULL for NULL or no memory). */
char *cli_strdup(const char *s);

/* Peak resident memory of this process in MiB. */
double cli_peak_mib(void);

/* Copy src to dst (src NULL: zero dst), `bytes` cut into `parts` spread over ex's threads. */
void cli_parallel_bytes(const nprfx_executor *ex, void *dst, const void *src, size_t bytes,
                        int parts);

#ifdef __cplusplus
}
#endif
#endif
