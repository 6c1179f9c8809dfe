/* nprfx — the context a caller passes to every call: error handler, limits, executor.
 *
 * Init structs begin with their size so fields can be appended without breaking callers built
 * against an older header (OpenEXRCore's convention). */
#ifndef NPRFX_CONTEXT_H
#define NPRFX_CONTEXT_H

#include "nprfx/exec.h"
#include "nprfx/result.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct nprfx_context nprfx_context;

typedef struct nprfx_context_init {
    size_t size;                       /* sizeof(nprfx_context_init) */
    nprfx_error_handler error_handler; /* NULL: messages are only kept for nprfx_last_error */
    void *error_user;
    const nprfx_executor *executor; /* NULL: run serially on the calling thread */
    /* Directory of the library's data files (the stipple node's dot sequence, ivs.bin); copied.
     * NULL, or a file missing there: what the file holds is generated when first needed, which
     * gives the same results, only later. */
    const char *data_dir;
} nprfx_context_init;

#define NPRFX_CONTEXT_INIT_DEFAULT                                                                 \
    {                                                                                              \
        sizeof(nprfx_context_init), NULL, NULL, NULL, NULL                                         \
    }

nprfx_result nprfx_context_create(const nprfx_context_init *init, nprfx_context **out);
void nprfx_context_destroy(nprfx_context *ctx);

/* The data directory given at creation, or NULL. */
const char *nprfx_context_data_dir(const nprfx_context *ctx);

/* The executor given at creation (never NULL: a serial one when none was given). */
const nprfx_executor *nprfx_context_executor(const nprfx_context *ctx);

/* Raise an error: formats the message, hands it to the handler, keeps a copy for
 * nprfx_last_error, and returns `code` so callers can write `return nprfx_error(ctx, ...)`.
 * ctx may be NULL (the message is then dropped). Safe from several threads. */
nprfx_result nprfx_error(nprfx_context *ctx, nprfx_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
nprfx_result nprfx_verror(nprfx_context *ctx, nprfx_result code, const char *fmt, va_list ap);

/* The last message raised through ctx ("" when none). Valid until the next error on ctx. */
const char *nprfx_last_error(const nprfx_context *ctx);

#ifdef __cplusplus
}
#endif
#endif
