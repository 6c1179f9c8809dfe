/* The paper node's per-instance cache: the texture depends on neither the frame nor the time
 * (core/looks/paper.c), so the pixels of the last window rendered serve every later frame with the same
 * params, copied instead of made again (750 ms a 1920x1080 frame of the watercolour kind on two
 * threads). It only saves work: a render with another window or other params makes the pixels
 * anew, bit for bit those of nprfx_paper_texture. */
#include <pthread.h>
#include <string.h>

#include "nprfx/context.h"
#include "nprfx/paper.h"

#include "base/internal_state.h"

typedef struct paper_cache {
    pthread_mutex_t lock; /* first: internal_state.h */
    nprfx_paper_params key;
    nprfx_image img; /* owned: the last window rendered */
    int valid;
} paper_cache;

void nprfx_paper_state_free(void *state)
{
    paper_cache *c = state;
    if (!c) return;
    nprfx_image_free(&c->img);
    internal_state_free(c);
}

double nprfx_paper_state_bytes(const nprfx_paper_params *p, int width, int height)
{
    int channels = p->output == NPRFX_PAPER_HEIGHT ? 1 : 4;
    return (double)width * height * channels * sizeof(float);
}

/* The whole params struct, bytes and all: a field added to it later is part of the key without
 * a second list here. The node's binder zeroes the struct, so padding compares equal; a caller's
 * stray padding can only cause a miss (a render), never a wrong hit. */
static int same_params(const nprfx_paper_params *a, const nprfx_paper_params *b)
{
    return memcmp(a, b, sizeof *a) == 0;
}

/* Rows of `window` from src to dst (same channel count). */
static void copy_window(const nprfx_image *src, nprfx_image *dst, nprfx_rect window)
{
    const int C = dst->channels, w = nprfx_rect_width(window);
    for (int y = window.y0; y < window.y1; y++) {
        const float *s = nprfx_image_at(src, window.x0, y);
        float *d = nprfx_image_at(dst, window.x0, y);
        if (src->pixel_stride == C && dst->pixel_stride == C) {
            memcpy(d, s, sizeof(float) * (size_t)w * (size_t)C);
            continue;
        }
        for (int x = 0; x < w; x++, s += src->pixel_stride, d += dst->pixel_stride)
            memcpy(d, s, sizeof(float) * (size_t)C);
    }
}

nprfx_result nprfx_paper_render_cached(nprfx_context *ctx, const nprfx_paper_params *p,
                                       nprfx_rect window, nprfx_image *out, void **state)
{
    window = out ? nprfx_rect_intersect(window, out->bounds) : window;
    paper_cache *c = state && p && out ? internal_state_get(state, sizeof *c) : NULL;
    if (!c || nprfx_rect_empty(window)) return nprfx_paper_texture(ctx, p, window, out);
    pthread_mutex_lock(&c->lock);
    nprfx_result r = NPRFX_OK;
    if (c->valid && same_params(&c->key, p) && c->img.channels == out->channels &&
        nprfx_rect_equal(nprfx_rect_intersect(c->img.bounds, window), window)) {
        copy_window(&c->img, out, window);
    } else if ((r = nprfx_paper_texture(ctx, p, window, out)) == NPRFX_OK) {
        c->valid = 0;
        if (!c->img.data || !nprfx_rect_equal(c->img.bounds, window) ||
            c->img.channels != out->channels) {
            nprfx_image_free(&c->img);
            if (nprfx_image_alloc(NULL, window, out->channels, &c->img) != NPRFX_OK)
                memset(&c->img, 0, sizeof c->img); /* no memory to keep it: no cache */
        }
        if (c->img.data) {
            copy_window(out, &c->img, window);
            c->key = *p;
            c->valid = 1;
        }
    }
    pthread_mutex_unlock(&c->lock);
    return r;
}

nprfx_result nprfx_paper_render(const nprfx_render_args *args, const nprfx_paper_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    return nprfx_paper_render_cached(args->ctx, p, args->window, args->output, args->state);
}
