/* nprfx — the context a caller passes to every call: error handler, limits, executor.
 *
 * Init structs begin with their size so fields can be appended without breaking callers built
 * against an older header (OpenEXRCore's convention). */
#ifndef NPRFX_CONTEXT_H
#define NPRFX_CONTEXT_H

#include <stdint.h>

#include "nprfx/exec.h"
#include "nprfx/result.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A dense optical flow solver handed in by the front end (nprfx/flow.h). */
typedef struct nprfx_flow_provider nprfx_flow_provider;

typedef struct nprfx_context_init {
    size_t size;                       /* sizeof(nprfx_context_init) */
    nprfx_error_handler error_handler; /* NULL: messages are only kept (nprfx_context_last_error) */
    void *error_user;
    const nprfx_executor *executor; /* NULL: run serially on the calling thread */
    /* Directory of the library's data files (the stipple node's dot sequence, ivs.bin); copied.
     * NULL, or a file missing there: what the file holds is generated when first needed, which
     * gives the same results, only later. */
    const char *data_dir;
    /* The optical flow solver the flow node calls (nprfx/flow.h; not copied: it must outlive the
     * context). NULL: none, and the flow node fails with a message saying how to get one.
     * Appended: older callers' shorter structs read as NULL here. */
    const nprfx_flow_provider *flow;
} nprfx_context_init;

#define NPRFX_CONTEXT_INIT_DEFAULT                                                                 \
    {                                                                                              \
        sizeof(nprfx_context_init), NULL, NULL, NULL, NULL, NULL                                   \
    }

NPRFX_API nprfx_result nprfx_context_create(const nprfx_context_init *init, nprfx_context **out);
NPRFX_API void nprfx_context_destroy(nprfx_context *ctx);

/* A context that raises its errors through `parent` with `prefix` and ": " before the message
 * ("node 'toon'" gives "node 'toon': blend: input 'layer' is not connected"), so a layer adds
 * what it knows without catching and re-raising. It shares the parent's executor and data
 * directory; the prefix is copied. Destroy it before the parent. */
NPRFX_API nprfx_result nprfx_context_create_scoped(nprfx_context *parent, const char *prefix,
                                                   nprfx_context **out);

/* The data directory given at creation, or NULL. */
NPRFX_API const char *nprfx_context_data_dir(const nprfx_context *ctx);

/* The flow provider given at creation (scoped contexts: their root's), or NULL. */
NPRFX_API const nprfx_flow_provider *nprfx_context_flow(const nprfx_context *ctx);

/* The front end's own data for callbacks that receive only a context (an nprfx_io a plug-in
 * serves its host's images through; NULL: none). Set on a root context; scoped contexts give
 * their root's. Not thread-safe against concurrent setting. */
NPRFX_API void nprfx_context_set_front_end(nprfx_context *ctx, void *data);
NPRFX_API void *nprfx_context_front_end(const nprfx_context *ctx);

/* The executor given at creation (never NULL: a serial one when none was given). */
NPRFX_API const nprfx_executor *nprfx_context_executor(const nprfx_context *ctx);

/* The bytes of image data work through ctx may hold at once: one image made in one piece (a plate
 * read, a node's frame) and a graph's frames together (UINT64_MAX: no bound). `origin` says what
 * set it, for messages ("--mem-limit"; copied, 63 bytes at most). Scoped contexts use the nearest
 * parent's. Without one, NPRFX_READ_LIMIT in the environment sets the bound, else half the
 * physical memory (nprfx_image_limit, nprfx/io.h). */
NPRFX_API void nprfx_context_set_memory_limit(nprfx_context *ctx, uint64_t bytes,
                                              const char *origin);
/* Whether a limit was set on ctx or a parent; *bytes and *origin (may be NULL) receive it. */
NPRFX_API int nprfx_context_memory_limit(const nprfx_context *ctx, uint64_t *bytes,
                                         const char **origin);

/* Raise an error: formats the message, hands it to the handler once (through the scopes' prefixes
 * up to the root context), keeps a copy in each context it passes, and returns `code` so callers
 * can write `return nprfx_error(ctx, ...)`. ctx may be NULL (the message is then dropped). Safe
 * from several threads. */
NPRFX_API nprfx_result nprfx_error(nprfx_context *ctx, nprfx_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
NPRFX_API nprfx_result nprfx_verror(nprfx_context *ctx, nprfx_result code, const char *fmt,
                                    va_list ap);

/* Copy the last message raised through ctx (with the prefixes of ctx and its parents as far as
 * ctx; "" when none) into buf (size bytes, always terminated); returns that error's code, or
 * NPRFX_OK when none was raised. Safe from several threads. */
NPRFX_API nprfx_result nprfx_context_last_error(const nprfx_context *ctx, char *buf, size_t size);

#ifdef __cplusplus
}
#endif
#endif
