/* The caller's context: where error messages go, and which executor runs parallel work. */
#include <pthread.h>
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
    pthread_mutex_t lock; /* guards last_error: render threads may raise errors concurrently */
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

void nprfx_context_destroy(nprfx_context *ctx)
{
    if (!ctx) return;
    pthread_mutex_destroy(&ctx->lock);
    free(ctx->data_dir);
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
    return ctx ? ctx->data_dir : NULL;
}

const nprfx_executor *nprfx_context_executor(const nprfx_context *ctx)
{
    return ctx && ctx->executor ? ctx->executor : &serial_executor;
}

nprfx_result nprfx_verror(nprfx_context *ctx, nprfx_result code, const char *fmt, va_list ap)
{
    if (!ctx) return code;
    char msg[NPRFX_MESSAGE_MAX];
    vsnprintf(msg, sizeof msg, fmt, ap);
    pthread_mutex_lock(&ctx->lock);
    memcpy(ctx->last_error, msg, sizeof msg);
    pthread_mutex_unlock(&ctx->lock);
    if (ctx->handler) ctx->handler(ctx->user, code, msg);
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

const char *nprfx_last_error(const nprfx_context *ctx)
{
    return ctx ? ctx->last_error : "";
}
