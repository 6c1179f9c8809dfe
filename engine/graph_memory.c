/* nprfx graph engine — frames under the memory limit (docs/design.md §1 "Memory"): a frame is
 * handed out only when it fits, after the pool's idle buffers and unpinned cached results, least
 * recently used first, have made room; a result leaves the cache once its last consumer at the
 * frame has run, and after each frame every result outside the temporal sources' window goes. */
#include <stdint.h>
#include <stdio.h>
#include "frame_pool.h"
#include "nprfx/graph.h"
#include "graph_cache.h"
#include "graph_frames.h"
#include "graph_memory.h"
#include "graph_model.h"
#include "nprfx/io.h"

/* Make room for `bytes` more under the limit, beside the caches nodes keep: the pool's idle
 * buffers first, then unpinned results, least recently used first. Whether it fits now. */
static int make_room(nprfx_graph *g, size_t bytes)
{
    if (g->mem_limit == UINT64_MAX) return 1;
    size_t kept = g->state_bytes;
    if (g->held_bytes + kept + frame_pool_idle_bytes(g->pool) + bytes <= g->mem_limit) return 1;
    frame_pool_trim(g->pool, 0);
    for (centry *e = g->tail, *prev; e && g->held_bytes + kept + bytes > g->mem_limit; e = prev) {
        prev = e->prev;
        if (!e->pins) internal_graph_cache_drop(g, e);
    }
    frame_pool_trim(g->pool, 0); /* the dropped results' buffers went back to the pool */
    return g->held_bytes + kept + bytes <= g->mem_limit;
}

/* A frame handed out: counted as held, and in node's --stats. */
static nprfx_result held(nprfx_graph *g, int node, size_t bytes, int reused)
{
    g->held_bytes += bytes;
    if (node >= 0 && node < g->count) {
        g->stats[node].bytes += bytes;
        if (!reused) g->stats[node].fresh_bytes += bytes;
    }
    internal_graph_note_peak(g);
    return NPRFX_OK;
}

static nprfx_result frame_alloc(nprfx_graph *g, int node, const char *what, nprfx_rect bounds,
                                int channels, int clear, nprfx_image *im)
{
    int w = nprfx_rect_width(bounds), h = nprfx_rect_height(bounds);
    nprfx_result r = nprfx_image_limit_check(g->ctx, what, w, h, channels, 0);
    if (r) return r;
    size_t bytes = (size_t)w * (size_t)h * (size_t)(channels > 0 ? channels : 0) * sizeof(float);
    /* writes in the background hold their frames pinned: the room comes after them */
    if (!make_room(g, bytes) && !(g->wait_writes && g->wait_writes(g) && make_room(g, bytes))) {
        char need[32], held[32], lim[32], kept[32], caches[64] = "";
        nprfx_format_bytes(need, sizeof need, bytes);
        nprfx_format_bytes(held, sizeof held, g->held_bytes);
        nprfx_format_bytes(lim, sizeof lim, g->mem_limit);
        if (g->state_bytes) {
            nprfx_format_bytes(kept, sizeof kept, g->state_bytes);
            snprintf(caches, sizeof caches, " and %s of caches nodes keep", kept);
        }
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY,
                           "%s %dx%d with %d channel%s needs %s while the graph holds %s of frames "
                           "it still reads%s: above the %s memory limit (%s)",
                           what, w, h, channels, channels == 1 ? "" : "s", need, held, caches, lim,
                           nprfx_memory_limit_origin(g->ctx));
    }
    int reused = 0;
    if ((r = frame_pool_alloc(g->pool, g->ctx, bounds, channels, clear, im, &reused))) return r;
    return held(g, node, bytes, reused);
}

nprfx_result internal_graph_frame_alloc(nprfx_graph *g, int node, const char *what,
                                        nprfx_rect bounds, int channels, nprfx_image *im)
{
    return frame_alloc(g, node, what, bounds, channels, 1, im);
}

nprfx_result internal_graph_frame_alloc_unset(nprfx_graph *g, int node, const char *what,
                                              nprfx_rect bounds, int channels, nprfx_image *im)
{
    return frame_alloc(g, node, what, bounds, channels, 0, im);
}

nprfx_result internal_graph_frame_alloc_spare(nprfx_graph *g, int node, nprfx_rect bounds,
                                              int channels, nprfx_image *im)
{
    size_t bytes = (size_t)nprfx_rect_width(bounds) * (size_t)nprfx_rect_height(bounds) *
                   (size_t)(channels > 0 ? channels : 0) * sizeof(float);
    if (g->mem_limit != UINT64_MAX) {
        if (g->held_bytes + g->state_bytes + bytes > g->mem_limit) return NPRFX_ERR_OUT_OF_MEMORY;
        if (g->held_bytes + g->state_bytes + frame_pool_idle_bytes(g->pool) + bytes > g->mem_limit)
            frame_pool_trim(g->pool, 0);
    }
    int reused = 0;
    if (nprfx_image_limit_check(NULL, "", nprfx_rect_width(bounds), nprfx_rect_height(bounds),
                                channels, 0) ||
        frame_pool_alloc(g->pool, NULL, bounds, channels, 0, im, &reused))
        return NPRFX_ERR_OUT_OF_MEMORY;
    return held(g, node, bytes, reused);
}

void internal_graph_consumed(nprfx_graph *g, centry *e)
{
    if (g->no_pool || !g->plan_ready) return;
    e->uses--;
    if (e->uses <= 0 && !e->pins && !g->plan_temporal[e->node]) internal_graph_cache_drop(g, e);
}

void internal_graph_unpin(nprfx_graph *g, centry *e)
{
    e->pins--;
    if (g->no_pool || !g->plan_ready) return;
    if (e->uses <= 0 && !e->pins && !g->plan_temporal[e->node]) internal_graph_cache_drop(g, e);
}

void internal_graph_frame_sweep(nprfx_graph *g)
{
    if (g->no_pool || !g->plan_ready) return;
    /* In order, a recursion over frames reads the frame before and this one: after frame f it
     * needs f (and f+1, not made yet), not f-1. Out of order nothing is kept that the same
     * offsets from the next frame would not read; a wrong guess costs a render, never a pixel. */
    /* 64 bits: frames a whole int apart (a caller's own frame order) have a step beyond int. */
    int64_t step = g->have_prev ? (int64_t)g->cur_frame - g->prev_frame : 1;
    int64_t next = (int64_t)g->cur_frame + step;
    /* This frame's own results always stay: at the first frame a recursion has read nothing
     * else yet, and will read this one next. */
    int64_t lo = g->have_win && g->win_lo < -step ? g->win_lo : -step;
    int64_t hi = g->have_win && g->win_hi > -step ? g->win_hi : -step;
    for (centry *e = g->tail, *prev; e; e = prev) {
        prev = e->prev;
        int64_t off = (int64_t)e->frame - next;
        if (e->pins || (g->plan_temporal[e->node] && off >= lo && off <= hi)) continue;
        internal_graph_cache_drop(g, e);
    }
    frame_pool_age(g->pool);
    internal_graph_cache_evict(g); /* the pool's idle buffers under the byte bound */
}
