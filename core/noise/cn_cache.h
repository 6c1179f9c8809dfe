/* The coherent-noise node's cache of pass states (cn_cache.c), for its temporal driver
 * (cn_temporal.c). Internal, never installed. */
#ifndef NPRFX_CN_CACHE_H
#define NPRFX_CN_CACHE_H

#include <pthread.h>
#include <stdint.h>

#include "nprfx/coherent_noise.h"

typedef struct cn_slot {
    int used;
    int64_t frame;
    uint64_t fingerprint; /* of the inputs read at this frame */
    nprfx_cn_state st;    /* value.data NULL until allocated */
} cn_slot;

typedef struct cn_pass {
    int dir;
    int64_t origin;
    int valid;
    int K;         /* checkpoint spacing (0: none) */
    cn_slot *ckpt; /* ncap checkpoints */
    int ncap;
    cn_slot *ring; /* the most recent run of states */
    int nring, ring_next;
    nprfx_cn_state scratch;
    /* The depth read by the latest step (frame depth_frame, of the state whose fingerprint is
     * depth_fp): the next in-order step needs it as the previous depth, and fetching another
     * frame can be costly in a host (an upstream render, a channel repack). */
    nprfx_image depth;
    int64_t depth_frame;
    uint64_t depth_fp;
    int depth_valid;
    /* The depth a step reads at its own frame once the confidence input has gated it: +inf
     * (background, so fresh noise) where the flow is not trusted. Allocated when first used. */
    nprfx_image gated;
} cn_pass;

typedef struct cn_cache {
    pthread_mutex_t lock; /* first: internal_state.h */
    uint64_t key;
    int have_key;
    cn_pass pass[2]; /* forward, backward */
    nprfx_image result;
    int64_t result_frame;
    uint64_t result_key, result_fp;
    int has_result;
    /* what the frames a render reads depend on, as the last render had it (cn_span_key) */
    uint64_t span_key;
    int have_span_key;
} cn_cache;

#define CN_HASH_INIT 0xcbf29ce484222325ull

/* Free a slot's state and mark it unused. */
void internal_cn_slot_free(cn_slot *s);
/* Free a pass's checkpoints, ring and buffers; the pass is zeroed (not valid). */
void internal_cn_pass_free(cn_pass *ps);
/* FNV-1a over bytes, from h (CN_HASH_INIT to start); the f64 and i64 forms hash a value. */
uint64_t internal_cn_hash_bytes(uint64_t h, const void *data, size_t n);
uint64_t internal_cn_hash_f64(uint64_t h, double v);
uint64_t internal_cn_hash_i64(uint64_t h, int64_t v);
/* A sparse fingerprint of an input view (a fixed 32x32 grid of samples plus its shape): cheap
 * enough for every render call, and enough to notice an upstream change. */
uint64_t internal_cn_fingerprint(uint64_t h, const nprfx_image *im);
/* For states of sb bytes, a budget and a span of n frames: the checkpoint spacing K (0: none),
 * the ring's length and the number of checkpoints. */
void internal_cn_pass_shape(size_t sb, size_t budget, int64_t n, int *K, int *nring, int *ncap);
/* The saved state of frame f (NULL: none). */
cn_slot *internal_cn_pass_find(cn_pass *ps, int64_t f);
/* The saved state nearest to f on the origin side (NULL: none). */
cn_slot *internal_cn_pass_nearest(cn_pass *ps, int64_t f);
/* Push the scratch state (frame f, fingerprint fp) into the ring; the replaced buffers become
 * the scratch. */
cn_slot *internal_cn_pass_push(cn_pass *ps, int64_t f, uint64_t fp);
/* Mark the pass to be configured again before its next use. */
void internal_cn_pass_invalidate(cn_pass *ps);

#endif
