/* nprfx core — the per-instance caches nodes keep in nprfx_render_args.state (never installed).
 * A cache is a struct whose FIRST member is a pthread_mutex_t that guards the rest; it only
 * saves work, so results never depend on it. */
#ifndef NPRFX_INTERNAL_STATE_H
#define NPRFX_INTERNAL_STATE_H

#include <stddef.h>

/* The cache in *slot, created zeroed (size bytes, mutex initialised) on first use. Two tiles of
 * the first render may race here: the loser of the compare-and-swap frees its copy. NULL when
 * out of memory. */
void *internal_state_get(void **slot, size_t size);

/* Destroy the mutex and free the cache (free what it points to first). NULL is ignored. */
void internal_state_free(void *state);

#endif
