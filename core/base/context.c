/* The caller's context: where error messages go, and which executor runs parallel work. */
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/context.h"

#define NPRFX_MESSAGE_MAX 1024

struct nprfx_context {
    nprfx_error_handler handler;
    void *user;
    const nprfx_executor *executor;
    char *data_dir;
    const nprfx_flow_provider *flow;
    void *front_end; /* nprfx_context_set_front_end: the root's */
    /* nprfx_context_set_memory_limit: the bound and what set it ("--mem-limit") */
    int have_memory_limit;
    uint64_t memory_limit;
    char memory_origin[64];
    nprfx_context *parent; /* scoped contexts: where messages go on, with `prefix` before them */
    char *prefix;
    pthread_mutex_t lock; /* guards last_*: render threads may raise errors concurrently */
    nprfx_result last_code;
    char last_error[NPRFX_MESSAGE_MAX];
};

nprfx_result nprfx_context_create(const nprfx_context_init *init, nprfx_context **out)
{
    if (!out) return NPRFX_ERR_INVALID_ARGUMENT;
    *out = NULL;
    /* Accept older, shorter init structs: read only the fields they have. */
    nprfx_context_init in = NPRFX_CONTEXT_INIT_DEFAULT;
    if (init) {
        if (init->size < offsetof(nprfx_context_init, executor) || init->size > sizeof in)
            return NPRFX_ERR_INVALID_ARGUMENT;
        memcpy(&in, init, init->size);
    }
    nprfx_context *ctx = calloc(1, sizeof *ctx);
    if (!ctx) return NPRFX_ERR_OUT_OF_MEMORY;
    ctx->handler = in.error_handler;
    ctx->user = in.error_user;
    ctx->executor = in.executor;
    ctx->flow = in.flow;
    if (in.data_dir) {
        size_t n = strlen(in.data_dir) + 1;
        if (!(ctx->data_dir = malloc(n))) {
            free(ctx);
            return NPRFX_ERR_OUT_OF_MEMORY;
        }
        memcpy(ctx->data_dir, in.data_dir, n);
    }
    pthread_mutex_init(&ctx->lock, NULL);
    *out = ctx;
    return NPRFX_OK;
}

nprfx_result nprfx_context_create_scoped(nprfx_context *parent, const char *prefix,
                                         nprfx_context **out)
{
    if (!out) return NPRFX_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!parent || !prefix) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = calloc(1, sizeof *ctx);
    size_t n = strlen(prefix) + 1;
    if (!ctx || !(ctx->prefix = malloc(n))) {
        free(ctx);
        return NPRFX_ERR_OUT_OF_MEMORY;
    }
    memcpy(ctx->prefix, prefix, n);
    ctx->parent = parent;
    ctx->executor = parent->executor;
    pthread_mutex_init(&ctx->lock, NULL);
    *out = ctx;
    return NPRFX_OK;
}

void nprfx_context_set_memory_limit(nprfx_context *ctx, uint64_t bytes, const char *origin)
{
    if (!ctx) return;
    ctx->have_memory_limit = 1;
    ctx->memory_limit = bytes;
    snprintf(ctx->memory_origin, sizeof ctx->memory_origin, "%s", origin ? origin : "");
}

int nprfx_context_memory_limit(const nprfx_context *ctx, uint64_t *bytes, const char **origin)
{
    /* A scoped context's own limit, else the nearest parent's: a graph's node scopes see the
     * limit its caller set. */
    for (; ctx; ctx = ctx->parent)
        if (ctx->have_memory_limit) {
            if (bytes) *bytes = ctx->memory_limit;
            if (origin) *origin = ctx->memory_origin;
            return 1;
        }
    return 0;
}

void nprfx_context_destroy(nprfx_context *ctx)
{
    if (!ctx) return;
    pthread_mutex_destroy(&ctx->lock);
    free(ctx->data_dir);
    free(ctx->prefix);
    free(ctx);
}

static void serial_for(void *impl, int count, int grain, nprfx_range_fn fn, void *user)
{
    (void)impl;
    (void)grain;
    if (count > 0) fn(user, 0, count, 0);
}
static int serial_workers(void *impl)
{
    return (void)impl, 1;
}
static const nprfx_executor serial_executor = {sizeof(nprfx_executor), NULL, serial_workers,
                                               serial_for};

const char *nprfx_context_data_dir(const nprfx_context *ctx)
{
    while (ctx && ctx->parent)
        ctx = ctx->parent;
    return ctx ? ctx->data_dir : NULL;
}

const nprfx_flow_provider *nprfx_context_flow(const nprfx_context *ctx)
{
    /* Scoped contexts hold none of their own: the root's is the one the front end gave. */
    while (ctx && ctx->parent)
        ctx = ctx->parent;
    return ctx ? ctx->flow : NULL;
}

void nprfx_context_set_front_end(nprfx_context *ctx, void *data)
{
    if (ctx) ctx->front_end = data;
}

void *nprfx_context_front_end(const nprfx_context *ctx)
{
    while (ctx && ctx->parent)
        ctx = ctx->parent;
    return ctx ? ctx->front_end : NULL;
}

const nprfx_executor *nprfx_context_executor(const nprfx_context *ctx)
{
    return ctx && ctx->executor ? ctx->executor : &serial_executor;
}

/* Keep msg as ctx's last message, then hand it on: to the parent with ctx's prefix, or at the
 * root to the handler, which so sees each message once, finished. `raised` is the context the
 * error was raised on. */
static void deliver(nprfx_context *ctx, const nprfx_context *raised, nprfx_result code,
                    const char *msg)
{
    pthread_mutex_lock(&ctx->lock);
    snprintf(ctx->last_error, sizeof ctx->last_error, "%s", msg);
    ctx->last_code = code;
    pthread_mutex_unlock(&ctx->lock);
    if (ctx->parent) {
        char longer[NPRFX_MESSAGE_MAX];
        snprintf(longer, sizeof longer, "%s: %s", ctx->prefix, msg);
        deliver(ctx->parent, raised, code, longer);
    } else if (ctx->handler) {
        ctx->handler(ctx->user, raised, code, msg);
    }
}

nprfx_result nprfx_verror(nprfx_context *ctx, nprfx_result code, const char *fmt, va_list ap)
{
    if (!ctx) return code;
    char msg[NPRFX_MESSAGE_MAX];
    vsnprintf(msg, sizeof msg, fmt, ap);
    deliver(ctx, ctx, code, msg);
    return code;
}

nprfx_result nprfx_error(nprfx_context *ctx, nprfx_result code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    nprfx_result r = nprfx_verror(ctx, code, fmt, ap);
    va_end(ap);
    return r;
}

nprfx_result nprfx_context_last_error(const nprfx_context *ctx, char *buf, size_t size)
{
    if (buf && size) buf[0] = 0;
    if (!ctx) return NPRFX_OK;
    /* The lock is not const, the message is: cast only to take it. */
    nprfx_context *c = (nprfx_context *)ctx;
    pthread_mutex_lock(&c->lock);
    if (buf && size) snprintf(buf, size, "%s", c->last_error);
    nprfx_result code = c->last_code;
    pthread_mutex_unlock(&c->lock);
    return code;
}
