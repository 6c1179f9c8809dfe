/* nprfx CLI — the runner's lowest layer: the context every command runs with, its memory limit
 * and peak memory (the clocks, strdup and the parallel copy are the engine's:
 * engine/engine_util.h). */
#ifndef NPRFX_CLI_UTIL_H
#define NPRFX_CLI_UTIL_H

#include <stddef.h>
#include <stdint.h>

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
/* The data directory: $NPRFX_DATA_DIR, else share/nprfx beside the executable (the build tree) or
 * ../share/nprfx (an install), the first holding ivs.bin; NULL when there is none. It holds the
 * sample style graphs too (graphs/, and pam/ that some of them read). */
const char *cli_data_dir(char *buf, size_t size);
/* The memory limit (--mem-limit; UINT64_MAX: none) of the contexts cli_env_init makes from now
 * on, over NPRFX_READ_LIMIT's. */
void cli_env_mem_limit(uint64_t bytes);
void cli_env_free(cli_env *env);

/* The last message raised through ctx, copied (valid until the next call from this thread). */
const char *cli_message(const nprfx_context *ctx);

/* Peak resident memory of this process in MiB. */
double cli_peak_mib(void);

/* Create dir and its missing parents, as the writers would before the first frame; 0 or -1
 * (errno set). */
int cli_make_dirs(const char *dir);

#ifdef __cplusplus
}
#endif
#endif
