/* nprfx graph engine — a pool of frame buffers for the graph engine (docs/design.md §1 "Memory").
 *
 * A graph allocates the same frames every frame: each node's output has the same size and
 * channels as at the frame before. Fresh frames above glibc's mmap threshold (32 MiB: one 1080p
 * RGBA float frame) come straight from the kernel and go back to it when freed, so every frame
 * paid its page faults again, inside the node's time. The pool keeps released buffers and hands
 * them out again to a request of the same size, zeroed as nprfx_image_alloc's calloc would give
 * them, so a node sees exactly what it saw before and outputs stay bit-identical. Idle buffers
 * are bounded: the caller trims them (frame_pool_trim) under its byte bounds.
 *
 * Not thread-safe: the engine allocates frames from its one evaluation thread. */
#ifndef NPRFX_CLI_FRAME_POOL_H
#define NPRFX_CLI_FRAME_POOL_H

#include <stddef.h>

#include "nprfx/nprfx.h"

typedef struct frame_pool frame_pool;

/* A pool; disabled != 0 makes it a pass-through (calloc and free, nothing kept): the runner's
 * --no-pool, which must give the same pixels. NULL on no memory. */
frame_pool *frame_pool_create(int disabled);
/* Frees every idle buffer and the pool. Buffers still out must be released before. */
void frame_pool_destroy(frame_pool *p);

/* An image of bounds x channels, from an idle buffer of the same size when there is one, zeroed
 * (clear) or not (the caller sets every pixel before reading any). *reused (may be NULL) tells
 * whether it was. */
nprfx_result frame_pool_alloc(frame_pool *p, nprfx_context *ctx, nprfx_rect bounds, int channels,
                              int clear, nprfx_image *out, int *reused);
/* Testing: reused buffers handed out uncleared are filled with NaN instead, so that a pixel a
 * caller fails to set shows in its output rather than an earlier frame's value. */
void frame_pool_poison(frame_pool *p, int on);
/* Give im's pixels (from frame_pool_alloc) back to the pool and reset im. */
void frame_pool_release(frame_pool *p, nprfx_image *im);

/* Bytes held idle in the pool. */
size_t frame_pool_idle_bytes(const frame_pool *p);
/* Free idle buffers, least recently released first, until at most max_idle bytes stay idle. */
void frame_pool_trim(frame_pool *p, size_t max_idle);
/* A frame has ended: free the idle buffers that waited through it without being taken (released
 * before it began), so that buffers of a size the graph no longer makes do not stay. */
void frame_pool_age(frame_pool *p);

#endif
