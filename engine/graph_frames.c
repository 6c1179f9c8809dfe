/* nprfx graph engine — the frames a graph holds: each frame buffer counted against the memory limit
 * as it is handed out, adopted or given back, the caches stateful nodes keep, the peak, the window
 * of frames temporal sources are read at, and the per-node costs (nprfx_graph_stats). */
#include <stdint.h>
#include <stdlib.h>
#include "frame_pool.h"
#include "nprfx/graph.h"
#include "nprfx/seq.h"
#include "graph_frames.h"
#include "graph_model.h"

size_t internal_graph_image_bytes(const nprfx_image *im)
{
    return (size_t)nprfx_rect_width(im->bounds) * (size_t)nprfx_rect_height(im->bounds) *
           (size_t)im->channels * sizeof(float);
}

void internal_graph_note_peak(nprfx_graph *g)
{
    size_t now = g->held_bytes + g->state_bytes + frame_pool_idle_bytes(g->pool);
    if (now > g->mem_peak) g->mem_peak = now;
}

uint64_t internal_graph_query_state(nprfx_graph *g, const gnode *n, const nprfx_value *params,
                                    int w, int h, const int *in_ch)
{
    nprfx_state_query q = {w, h, g->first_frame, g->last_frame, in_ch};
    double bytes = 0;
    if (nprfx_node_state_bytes(n->ctx, n->desc, params, &q, &bytes)) return 0;
    return bytes < 1.8e19 ? (uint64_t)bytes : UINT64_MAX / 2;
}

void internal_graph_count_state(nprfx_graph *g, gnode *n, int w, int h, const int *in_ch,
                                const nprfx_value *params)
{
    if (n->state_counted || n->kind != GK_NODE || !(n->desc->flags & NPRFX_NODE_STATEFUL)) return;
    n->state_counted = 1;
    g->state_bytes += (size_t)internal_graph_query_state(g, n, params, w, h, in_ch);
    internal_graph_note_peak(g);
}

void internal_graph_frame_adopt(nprfx_graph *g, int node, const nprfx_image *im)
{
    size_t bytes = internal_graph_image_bytes(im);
    g->held_bytes += bytes;
    if (node >= 0 && node < g->count) {
        g->stats[node].bytes += bytes;
        g->stats[node].fresh_bytes += bytes;
    }
    internal_graph_note_peak(g);
}

void internal_graph_frame_release(nprfx_graph *g, nprfx_image *im)
{
    if (!im || !im->data) return;
    size_t bytes = internal_graph_image_bytes(im);
    g->held_bytes -= bytes < g->held_bytes ? bytes : g->held_bytes;
    frame_pool_release(g->pool, im);
}

void internal_graph_frame_begin(nprfx_graph *g, int frame)
{
    if (g->gen) {
        g->prev_frame = g->cur_frame;
        g->have_prev = 1;
    }
    g->gen++;
    g->cur_frame = frame;
    g->have_win = 0;
}

void internal_graph_touch(nprfx_graph *g, centry *e)
{
    if (!g->plan_ready || e->node < 0 || e->node >= g->count || !g->plan_temporal[e->node]) return;
    int off = e->frame - g->cur_frame;
    if (!g->have_win || off < g->win_lo) g->win_lo = off;
    if (!g->have_win || off > g->win_hi) g->win_hi = off;
    g->have_win = 1;
}

int nprfx_graph_stats(const nprfx_graph *g, const nprfx_graph_node_stats **stats)
{
    int count = g->flows_wired ? g->count : g->visible;
    for (int i = 0; i < count; i++) {
        nprfx_graph_node_stats *s = &g->stats[i];
        const gnode *n = &g->nodes[i];
        s->name = n->name;
        s->kind = n->kind == GK_NODE ? 0 : n->kind == GK_READ ? 1 : n->kind == GK_SYNTH ? 2 : 3;
        s->type = n->kind == GK_NODE    ? n->desc->id
                  : n->kind == GK_READ  ? "read"
                  : n->kind == GK_SYNTH ? "synth"
                                        : "write";
    }
    *stats = g->stats;
    return count;
}

size_t nprfx_graph_mem_peak(const nprfx_graph *g)
{
    return g->mem_peak;
}

nprfx_result internal_graph_frame_ok(nprfx_graph *g, int frame)
{
    if (frame >= NPRFX_FRAME_MIN && frame <= NPRFX_FRAME_MAX) return NPRFX_OK;
    return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_RANGE,
                       "frame %d is outside the frames nprfx renders (%d to %d)", frame,
                       NPRFX_FRAME_MIN, NPRFX_FRAME_MAX);
}
