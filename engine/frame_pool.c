/* nprfx graph engine — the frame-buffer pool of frame_pool.h. A graph has few distinct frame sizes (a
 * plate, a few channel counts), so the idle buffers are a short list searched linearly, most
 * recently released first (its pages are the likeliest to be in cache). */
#include "frame_pool.h"
#include "engine_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct idle_buf {
    float *data;
    size_t floats;
    unsigned epoch;        /* the frame it was released in */
    struct idle_buf *next; /* most recently released first */
} idle_buf;

struct frame_pool {
    int disabled, poison;
    unsigned epoch;
    idle_buf *idle;
    size_t idle_bytes;
};

frame_pool *frame_pool_create(int disabled)
{
    frame_pool *p = calloc(1, sizeof *p);
    if (p) p->disabled = disabled;
    return p;
}

void frame_pool_destroy(frame_pool *p)
{
    if (!p) return;
    frame_pool_trim(p, 0);
    free(p);
}

/* Zeroing a reused frame, on every thread, in 1 MiB parts: a graph clears a few hundred MB a frame
 * at 1080p, which on the evaluating thread alone was a tenth of the bench graph's time. */
static void zero_floats(nprfx_context *ctx, float *data, size_t floats)
{
    size_t bytes = floats * sizeof(float), parts = (bytes + ((size_t)1 << 20) - 1) >> 20;
    engine_parallel_bytes(ctx ? nprfx_context_executor(ctx) : NULL, data, NULL, bytes,
                          parts < 3 ? 1 : (int)parts);
}

void frame_pool_poison(frame_pool *p, int on)
{
    if (p) p->poison = on;
}

nprfx_result frame_pool_alloc(frame_pool *p, nprfx_context *ctx, nprfx_rect bounds, int channels,
                              int clear, nprfx_image *out, int *reused)
{
    if (reused) *reused = 0;
    size_t w = (size_t)nprfx_rect_width(bounds), h = (size_t)nprfx_rect_height(bounds);
    size_t floats = w * h * (size_t)(channels > 0 ? channels : 0);
    if (!p->disabled && floats > 0 && channels >= 1)
        for (idle_buf **link = &p->idle; *link; link = &(*link)->next) {
            idle_buf *b = *link;
            if (b->floats != floats) continue;
            *link = b->next;
            p->idle_bytes -= floats * sizeof(float);
            memset(out, 0, sizeof *out);
            out->data = b->data;
            free(b);
            /* calloc's zeros: a node that writes only part of its window, or accumulates into
             * its output (splats), must see what it saw in a fresh frame. */
            if (clear)
                zero_floats(ctx, out->data, floats);
            else if (p->poison)
                for (size_t i = 0; i < floats; i++)
                    out->data[i] = NAN;
            out->pixel_stride = channels;
            out->row_stride = (ptrdiff_t)(w * (size_t)channels);
            out->channels = channels;
            out->bounds = bounds;
            if (reused) *reused = 1;
            return NPRFX_OK;
        }
    return nprfx_image_alloc(ctx, bounds, channels, out);
}

void frame_pool_release(frame_pool *p, nprfx_image *im)
{
    if (!im || !im->data) return;
    size_t floats = (size_t)nprfx_rect_width(im->bounds) * (size_t)nprfx_rect_height(im->bounds) *
                    (size_t)im->channels;
    idle_buf *b = p->disabled || !floats ? NULL : malloc(sizeof *b);
    if (!b) {
        nprfx_image_free(im);
        return;
    }
    b->data = im->data;
    b->floats = floats;
    b->epoch = p->epoch;
    b->next = p->idle;
    p->idle = b;
    p->idle_bytes += floats * sizeof(float);
    memset(im, 0, sizeof *im);
}

size_t frame_pool_idle_bytes(const frame_pool *p)
{
    return p ? p->idle_bytes : 0;
}

void frame_pool_trim(frame_pool *p, size_t max_idle)
{
    while (p->idle_bytes > max_idle && p->idle) {
        /* the least recently released is the last one */
        idle_buf **link = &p->idle;
        while ((*link)->next)
            link = &(*link)->next;
        idle_buf *b = *link;
        *link = NULL;
        p->idle_bytes -= b->floats * sizeof(float);
        free(b->data);
        free(b);
    }
}

void frame_pool_age(frame_pool *p)
{
    for (idle_buf **link = &p->idle; *link;) {
        idle_buf *b = *link;
        if (b->epoch == p->epoch) {
            link = &b->next;
            continue;
        }
        *link = b->next;
        p->idle_bytes -= b->floats * sizeof(float);
        free(b->data);
        free(b);
    }
    p->epoch++;
}
