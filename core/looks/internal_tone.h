/* nprfx core — the tone node's per-instance cache, shared by its render (tone.c) and its
 * measurement's text form (tone_state.c). Never installed. */
#ifndef NPRFX_INTERNAL_TONE_H
#define NPRFX_INTERNAL_TONE_H

#include <pthread.h>
#include <stdint.h>

/* What a measured range depends on: the param values that pick the samples and percentiles,
 * the shot, and a fingerprint of every frame's samples. A render compares the fingerprint of
 * its own frame with the stored one, so an upstream change is noticed and the range measured
 * again: the cache saves work and never changes a result. */
typedef struct internal_tone_cache {
    pthread_mutex_t lock; /* first: internal_state.h */
    int valid;
    int range, reference, first, last;
    double low, high;
    double lo, hi;
    int nframes;
    uint64_t *hash; /* one per frame of the shot (RANGE_FRAME: one) */
} internal_tone_cache;

#endif
