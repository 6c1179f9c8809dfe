/* nprfx graph engine — its lowest layer: the clocks, strdup and a parallel byte copy, which the
 * engine and the runner above it share. Includes nothing of the engine's other files. */
#ifndef NPRFX_ENGINE_UTIL_H
#define NPRFX_ENGINE_UTIL_H

#include <stddef.h>

#include "nprfx/nprfx.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Monotonic clock in seconds. */
double engine_now(void);
/* The process's CPU time in seconds, all threads (CLOCK_PROCESS_CPUTIME_ID). */
double engine_cpu_now(void);

/* A malloc'd copy of s (NULL for NULL or no memory). */
char *engine_strdup(const char *s);
/* The whole of a small text file (`what` names it in messages: "graph file"), malloc'd and
 * NUL-terminated; NULL with NPRFX_ERR_IO raised on ctx when it cannot be read or is not below
 * `most` bytes. */
char *engine_read_text(nprfx_context *ctx, const char *path, const char *what, long most);
/* Free n strings and the array that holds them (NULL: nothing). */
void engine_names_free(char **names, int n);

/* Copy src to dst (src NULL: zero dst), `bytes` cut into `parts` spread over ex's threads. */
void engine_parallel_bytes(const nprfx_executor *ex, void *dst, const void *src, size_t bytes,
                           int parts);

#ifdef __cplusplus
}
#endif
#endif
