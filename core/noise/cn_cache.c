/* The coherent-noise node's per-instance cache of pass states (cn_temporal.c drives it): the
 * checkpoints and ring of recent states of each pass, how many of each fit the memory bound, and
 * the fingerprints that notice a changed input. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "base/internal_state.h"
#include "cn_cache.h"
#include "nprfx/rng.h"

void internal_cn_slot_free(cn_slot *s)
{
    nprfx_cn_state_free(&s->st);
    s->used = 0;
}

void internal_cn_pass_free(cn_pass *ps)
{
    for (int i = 0; i < ps->ncap; i++)
        internal_cn_slot_free(&ps->ckpt[i]);
    for (int i = 0; i < ps->nring; i++)
        internal_cn_slot_free(&ps->ring[i]);
    free(ps->ckpt);
    free(ps->ring);
    nprfx_cn_state_free(&ps->scratch);
    nprfx_image_free(&ps->depth);
    nprfx_image_free(&ps->gated);
    memset(ps, 0, sizeof *ps);
}

void nprfx_coherent_noise_state_free(void *state)
{
    cn_cache *c = state;
    if (!c) return;
    internal_cn_pass_free(&c->pass[0]);
    internal_cn_pass_free(&c->pass[1]);
    nprfx_image_free(&c->result);
    internal_state_free(c);
}

/* FNV-1a over bytes. */
uint64_t internal_cn_hash_bytes(uint64_t h, const void *data, size_t n)
{
    return nprfx_fnv1a(h, data, n);
}
uint64_t internal_cn_hash_f64(uint64_t h, double v)
{
    return internal_cn_hash_bytes(h, &v, sizeof v);
}
uint64_t internal_cn_hash_i64(uint64_t h, int64_t v)
{
    return internal_cn_hash_bytes(h, &v, sizeof v);
}

/* A sparse fingerprint of an input view (a fixed 32x32 grid of samples plus its shape): cheap
 * enough for every render call, and enough to notice an upstream change in a host that keeps the
 * instance alive. */
uint64_t internal_cn_fingerprint(uint64_t h, const nprfx_image *im)
{
    if (!im || !im->data) return internal_cn_hash_bytes(h, "none", 4);
    h = internal_cn_hash_bytes(h, &im->bounds, sizeof im->bounds);
    h = internal_cn_hash_bytes(h, &im->channels, sizeof im->channels);
    int w = nprfx_rect_width(im->bounds), ht = nprfx_rect_height(im->bounds);
    for (int j = 0; j < 32; j++)
        for (int i = 0; i < 32; i++) {
            int x = im->bounds.x0 + (int)(((int64_t)(2 * i + 1) * w) / 64);
            int y = im->bounds.y0 + (int)(((int64_t)(2 * j + 1) * ht) / 64);
            h = internal_cn_hash_bytes(h, nprfx_image_at(im, x, y),
                                       sizeof(float) * (size_t)im->channels);
        }
    return h;
}

/* Sizes the pass for a span of n frames within the byte budget: checkpoints every K frames and
 * a ring of K recent states (sqrt decomposition: any frame is at most K steps from a checkpoint
 * and in-order or reverse-order rendering recomputes each block once). */
void internal_cn_pass_shape(size_t sb, size_t budget, int64_t n, int *K, int *nring, int *ncap)
{
    int64_t m = sb ? (int64_t)(budget / sb) : 0;
    if (n < 1) n = 1;
    int64_t k = (int64_t)ceil(sqrt((double)n));
    if (m >= 2 * k + 1) {
        *K = (int)k;
        *nring = (int)k;
    } else if (m >= 2) {
        *nring = 1;
        *K = (int)((n + (m - 1) - 1) / (m - 1));
    } else {
        *nring = 1;
        *K = 0;
    }
    *ncap = *K > 0 ? (int)(n / *K + 2) : 0;
}

cn_slot *internal_cn_pass_find(cn_pass *ps, int64_t f)
{
    for (int i = 0; i < ps->nring; i++)
        if (ps->ring[i].used && ps->ring[i].frame == f) return &ps->ring[i];
    for (int i = 0; i < ps->ncap; i++)
        if (ps->ckpt[i].used && ps->ckpt[i].frame == f) return &ps->ckpt[i];
    return NULL;
}

/* The saved state nearest to f on the origin side (NULL: none). */
cn_slot *internal_cn_pass_nearest(cn_pass *ps, int64_t f)
{
    cn_slot *best = NULL;
    int64_t bd = INT64_MAX;
    for (int pass = 0; pass < 2; pass++) {
        cn_slot *s = pass ? ps->ckpt : ps->ring;
        int n = pass ? ps->ncap : ps->nring;
        for (int i = 0; i < n; i++) {
            if (!s[i].used) continue;
            int64_t d = (f - s[i].frame) * ps->dir;
            if (d >= 0 && (s[i].frame - ps->origin) * ps->dir >= 0 && d < bd) {
                bd = d;
                best = &s[i];
            }
        }
    }
    return best;
}

/* Push the scratch state (frame f) into the ring; the replaced buffers become the scratch. */
cn_slot *internal_cn_pass_push(cn_pass *ps, int64_t f, uint64_t fp)
{
    cn_slot *s = &ps->ring[ps->ring_next];
    ps->ring_next = (ps->ring_next + 1) % ps->nring;
    nprfx_cn_state t = s->st;
    s->st = ps->scratch;
    ps->scratch = t;
    s->used = 1;
    s->frame = f;
    s->fingerprint = fp;
    return s;
}

void internal_cn_pass_invalidate(cn_pass *ps)
{
    ps->valid = 0;
}
