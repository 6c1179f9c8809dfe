/* nprfx — result codes and the per-context error channel.
 *
 * Every public function returns an nprfx_result. The codes are plain ints so the ABI does not
 * change when a code is added; the enum only names them. Messages never go to a process-global
 * buffer: they are delivered to the handler of the nprfx_context the caller passed in, which keeps
 * the library re-entrant inside a host that runs several instances at once. */
#ifndef NPRFX_RESULT_H
#define NPRFX_RESULT_H

#include <stdarg.h>
#include <stddef.h>

#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef int nprfx_result;

enum nprfx_result_code {
    NPRFX_OK = 0,
    NPRFX_ERR_OUT_OF_MEMORY = 1,
    NPRFX_ERR_INVALID_ARGUMENT = 2, /* a NULL pointer, a bad size field, an impossible request */
    NPRFX_ERR_MISSING_INPUT = 3,    /* a required input, layer or channel is absent */
    NPRFX_ERR_SIZE_MISMATCH = 4,    /* inputs of different sizes where one size is required */
    NPRFX_ERR_IO = 5,               /* a file could not be read or written */
    NPRFX_ERR_UNKNOWN_NODE = 6,
    NPRFX_ERR_UNKNOWN_PARAM = 7,
    NPRFX_ERR_OUT_OF_RANGE = 8, /* a value outside a parameter's hard range */
    NPRFX_ERR_PARSE = 9,        /* malformed text: a graph file, a value, a frame range */
    NPRFX_ERR_CANCELLED = 10,
    NPRFX_ERR_UNSUPPORTED = 11,
    NPRFX_ERR_INTERNAL = 12
};

/* A short stable name for a code ("missing-input"); never NULL. */
NPRFX_API const char *nprfx_result_name(nprfx_result code);

typedef struct nprfx_context nprfx_context;

/* Receives every error message raised through a context, once, finished: `ctx` is the context it
 * was raised on (a scoped one's prefixes already applied), `message` the whole text. Called from
 * the thread that raised it; the handler must be thread-safe when the context is shared by
 * several threads. */
typedef void (*nprfx_error_handler)(void *user, const nprfx_context *ctx, nprfx_result code,
                                    const char *message);

#ifdef __cplusplus
}
#endif
#endif
