/* nprfx CLI — the graph's memory plan (issue 16, docs/design.md §1 "Memory").
 *
 * The cache alone kept every result until its byte bound pushed it out: a graph over 1080p plates
 * held 2 GiB of frames it would never read again. The runner knows the graph, so it plans:
 *  - each result knows how many inputs read it at its frame (plan_uses); when the last of them
 *    has rendered, the result leaves the cache at once and its buffer goes back to the pool;
 *  - a node that some temporal node reads at other frames (what the node declares through
 *    nprfx_node_frames_needed) keeps its results past the frame; after each frame only those
 *    touched during it stay (the frames its temporal readers' window is working in), and the
 *    cache's byte bound still caps them;
 *  - every frame buffer comes from the frame pool (frame_pool.h) and goes back to it, so a frame
 *    of the same size is not faulted in again;
 *  - every allocation is checked against the memory limit (io_limits.h) before it is made, and
 *    nprfx_graph_plan estimates the peak from the graph and the frame size before frame 1.
 * Results never depend on any of it: a result dropped too early is rendered again, bit for bit
 * (docs/design.md §1, "a cache may save work, never change a result"). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal_graph.h"
#include "io.h"
#include "io_limits.h"
#include "nprfx/synth.h"

/* Whether temporal node n reads input k at frames other than the one it renders, asked at the
 * shot's first, middle and last frames; when the node cannot say, it is taken to. */
static int reads_other_frames(const nprfx_graph *g, const gnode *n, int k)
{
    const nprfx_node_desc *d = n->desc;
    if (!(d->flags & NPRFX_NODE_TEMPORAL)) return 0;
    int in_ch[32];
    for (int j = 0; j < d->num_inputs && j < 32; j++)
        in_ch[j] = n->inputs[j].src < 0 ? 0 : d->inputs[j].channels > 0 ? d->inputs[j].channels : 1;
    int times[3] = {g->first_frame, g->first_frame + (g->last_frame - g->first_frame) / 2,
                    g->last_frame};
    for (int t = 0; t < 3; t++) {
        nprfx_frames_query q = {times[t], g->first_frame, g->last_frame, in_ch};
        nprfx_frame_range r[NPRFX_MAX_FRAME_RANGES];
        int nr = 0;
        if (d->num_inputs > 32 || nprfx_node_frames_needed(NULL, d, n->params, &q, k, r, &nr))
            return 1;
        for (int i = 0; i < nr; i++)
            if (r[i].first != times[t] || r[i].last != times[t]) return 1;
    }
    return 0;
}

nprfx_result internal_graph_plan_build(nprfx_graph *g)
{
    if (g->plan_ready) return NPRFX_OK;
    free(g->plan_uses);
    free(g->plan_temporal);
    g->plan_uses = calloc((size_t)(g->count ? g->count : 1), sizeof *g->plan_uses);
    g->plan_temporal = calloc((size_t)(g->count ? g->count : 1), 1);
    if (!g->plan_uses || !g->plan_temporal)
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory planning the graph");
    for (int i = 0; i < g->count; i++) {
        const gnode *n = &g->nodes[i];
        for (int k = 0; k < n->ninputs; k++) {
            int src = n->inputs[k].src;
            if (src < 0) continue;
            g->plan_uses[src]++;
            if (n->kind == GK_NODE && reads_other_frames(g, n, k)) g->plan_temporal[src] = 1;
        }
    }
    g->plan_ready = 1;
    return NPRFX_OK;
}

static size_t image_bytes(const nprfx_image *im)
{
    return (size_t)nprfx_rect_width(im->bounds) * (size_t)nprfx_rect_height(im->bounds) *
           (size_t)im->channels * sizeof(float);
}

static void note_peak(nprfx_graph *g)
{
    size_t now = g->held_bytes + nprfx_frame_pool_idle_bytes(g->pool);
    if (now > g->mem_peak) g->mem_peak = now;
}

/* Make room for `bytes` more under the limit: the pool's idle buffers first, then unpinned
 * results, least recently used first. Whether it fits now. */
static int make_room(nprfx_graph *g, size_t bytes)
{
    if (g->mem_limit == UINT64_MAX) return 1;
    if (g->held_bytes + nprfx_frame_pool_idle_bytes(g->pool) + bytes <= g->mem_limit) return 1;
    nprfx_frame_pool_trim(g->pool, 0);
    for (centry *e = g->tail, *prev; e && g->held_bytes + bytes > g->mem_limit; e = prev) {
        prev = e->prev;
        if (!e->pins) internal_graph_cache_drop(g, e);
    }
    return g->held_bytes + bytes <= g->mem_limit;
}

nprfx_result internal_graph_frame_alloc(nprfx_graph *g, int node, const char *what,
                                        nprfx_rect bounds, int channels, nprfx_image *im)
{
    int w = nprfx_rect_width(bounds), h = nprfx_rect_height(bounds);
    nprfx_result r = nprfx_image_limit_check(g->ctx, what, w, h, channels, 0);
    if (r) return r;
    size_t bytes = (size_t)w * (size_t)h * (size_t)(channels > 0 ? channels : 0) * sizeof(float);
    if (!make_room(g, bytes)) {
        char need[32], held[32], lim[32];
        nprfx_format_bytes(need, sizeof need, bytes);
        nprfx_format_bytes(held, sizeof held, g->held_bytes);
        nprfx_format_bytes(lim, sizeof lim, g->mem_limit);
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY,
                           "%s %dx%d with %d channel%s needs %s while the graph holds %s of frames "
                           "it still reads: above the %s memory limit (%s)",
                           what, w, h, channels, channels == 1 ? "" : "s", need, held, lim,
                           nprfx_mem_limit_origin());
    }
    int reused = 0;
    if ((r = nprfx_frame_pool_alloc(g->pool, g->ctx, bounds, channels, im, &reused))) return r;
    g->held_bytes += bytes;
    if (node >= 0 && node < g->count) {
        g->stats[node].bytes += bytes;
        if (!reused) g->stats[node].fresh_bytes += bytes;
    }
    note_peak(g);
    return NPRFX_OK;
}

void internal_graph_frame_adopt(nprfx_graph *g, int node, const nprfx_image *im)
{
    size_t bytes = image_bytes(im);
    g->held_bytes += bytes;
    if (node >= 0 && node < g->count) {
        g->stats[node].bytes += bytes;
        g->stats[node].fresh_bytes += bytes;
    }
    note_peak(g);
}

void internal_graph_frame_release(nprfx_graph *g, nprfx_image *im)
{
    if (!im || !im->data) return;
    size_t bytes = image_bytes(im);
    g->held_bytes -= bytes < g->held_bytes ? bytes : g->held_bytes;
    nprfx_frame_pool_release(g->pool, im);
}

void internal_graph_consumed(nprfx_graph *g, centry *e)
{
    if (g->no_pool || !g->plan_ready) return;
    e->uses--;
    if (e->uses <= 0 && !e->pins && !g->plan_temporal[e->node]) internal_graph_cache_drop(g, e);
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

void internal_graph_frame_sweep(nprfx_graph *g)
{
    if (g->no_pool || !g->plan_ready) return;
    /* In order, a recursion over frames reads the frame before and this one: after frame f it
     * needs f (and f+1, not made yet), not f-1. Out of order nothing is kept that the same
     * offsets from the next frame would not read; a wrong guess costs a render, never a pixel. */
    int step = g->have_prev ? g->cur_frame - g->prev_frame : 1;
    int next = g->cur_frame + step;
    /* This frame's own results always stay: at the first frame a recursion has read nothing
     * else yet, and will read this one next. */
    int lo = g->have_win && g->win_lo < -step ? g->win_lo : -step;
    int hi = g->have_win && g->win_hi > -step ? g->win_hi : -step;
    for (centry *e = g->tail, *prev; e; e = prev) {
        prev = e->prev;
        int off = e->frame - next;
        if (e->pins || (g->plan_temporal[e->node] && off >= lo && off <= hi)) continue;
        internal_graph_cache_drop(g, e);
    }
    internal_graph_cache_evict(g); /* the pool's idle buffers under the byte bound */
}

int nprfx_graph_stats(const nprfx_graph *g, const nprfx_graph_node_stats **stats)
{
    for (int i = 0; i < g->count; i++) {
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
    return g->count;
}

size_t nprfx_graph_mem_peak(const nprfx_graph *g)
{
    return g->mem_peak;
}

nprfx_result nprfx_graph_synthesize_reads(nprfx_graph *g, int w, int h, const char *scene)
{
    for (int i = 0; i < g->count; i++) {
        gnode *n = &g->nodes[i];
        if (n->kind != GK_READ && n->kind != GK_SYNTH) continue;
        if (n->kind == GK_READ) {
            char *s = internal_graph_strdup(scene);
            if (!s) return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
            free(n->scene);
            n->scene = s;
            n->kind = GK_SYNTH;
        }
        n->width = w;
        n->height = h;
    }
    if (g->fmt_text) {
        char buf[64];
        snprintf(buf, sizeof buf, "%dx%d", w, h);
        char *s = internal_graph_strdup(buf);
        if (!s) return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        free(g->fmt_text);
        g->fmt_text = s;
    }
    internal_graph_cache_clear(g);
    g->plan_ready = 0;
    nprfx_result r = nprfx_image_limit(g->ctx, &g->mem_limit);
    return r ? r : internal_graph_check_limits(g);
}

/* ---------------------------------------------------------------- the estimate ---- */

/* One node's frame in the estimate: its size, channels and their names. */
typedef struct shape {
    int w, h, channels, known;
    char **names; /* owned, channels of them */
} shape;

static void shape_free(shape *s)
{
    for (int c = 0; s->names && c < s->channels; c++)
        free(s->names[c]);
    free(s->names);
    memset(s, 0, sizeof *s);
}

static uint64_t shape_bytes(const shape *s)
{
    return (uint64_t)s->w * (uint64_t)s->h * (uint64_t)s->channels * sizeof(float);
}

/* The shape of node i at frame from its inputs' shapes (all known); non-zero when it cannot be
 * told without rendering (the render then reports whatever is wrong). */
static int shape_of(nprfx_graph *g, int i, int frame, shape *sh, uint64_t *scratch)
{
    gnode *n = &g->nodes[i];
    *scratch = 0;
    if (n->kind == GK_SYNTH) {
        int nc = nprfx_synth_channel_count();
        sh->names = internal_graph_names_dup(nprfx_synth_channel_names(), nc);
        if (!sh->names) return 1;
        sh->w = n->width;
        sh->h = n->height;
        sh->channels = nc;
        sh->known = 1;
        return 0;
    }
    if (n->kind == GK_READ) {
        char file[4096];
        internal_graph_resolve_path(g, g->base_dir, n->path, frame, file, sizeof file);
        nprfx_file_info info;
        memset(&info, 0, sizeof info);
        if (nprfx_io_info(g->ctx, file, &info)) return 1;
        int extra = n->vectors && strcmp(n->vectors, "none") ? 4 : 0;
        sh->names = calloc((size_t)(info.nchannels + extra), sizeof *sh->names);
        for (int c = 0; sh->names && c < info.nchannels; c++)
            sh->names[c] = internal_graph_strdup(info.names[c]);
        for (int c = 0; sh->names && c < extra; c++)
            sh->names[info.nchannels + c] = internal_graph_strdup(internal_graph_motion_names[c]);
        sh->w = nprfx_rect_width(info.bounds);
        sh->h = nprfx_rect_height(info.bounds);
        sh->channels = info.nchannels + extra;
        nprfx_file_info_free(&info);
        if (!sh->names) return 1;
        sh->known = 1;
        return 0;
    }
    return -1; /* processing nodes: by the caller, which has the inputs' shapes */
}

/* The bytes of the channels (idx, count of them) an input packs out of a source of nc channels,
 * as internal_graph_select_input does: 0 when it reads them in place. */
static uint64_t packed_bytes(const shape *src, const int *idx, int count)
{
    int contiguous = 1;
    for (int c = 1; c < count; c++)
        contiguous &= idx[c] == idx[0] + c;
    if (contiguous && src->channels <= 2 * count) return 0;
    return (uint64_t)src->w * (uint64_t)src->h * (uint64_t)count * sizeof(float);
}

static int node_shape(nprfx_graph *g, int i, const shape *shapes, shape *sh, uint64_t *scratch)
{
    gnode *n = &g->nodes[i];
    const nprfx_node_desc *d = n->desc;
    int in_ch[32] = {0}, have = 0;
    *scratch = 0;
    if (d->num_inputs > 32) return 1;
    for (int k = 0; k < d->num_inputs; k++) {
        int src = n->inputs[k].src;
        if (src < 0) continue;
        const shape *s = &shapes[src];
        if (!s->known) return 1;
        int idx[256], count = 0;
        if (internal_graph_input_channels(g, n, k, (const char *const *)s->names, s->channels, idx,
                                          &count))
            return 1;
        in_ch[k] = count;
        *scratch += packed_bytes(s, idx, count);
        if ((d->inputs[k].flags & NPRFX_INPUT_UNALIGNED) || have) continue;
        sh->w = s->w;
        sh->h = s->h;
        have = 1;
    }
    if (!have && (!g->fmt_text || sscanf(g->fmt_text, "%dx%d", &sh->w, &sh->h) != 2)) return 1;
    nprfx_output_info oi;
    if (nprfx_node_output_info(NULL, d, n->params, in_ch, &oi)) return 1;
    sh->names = internal_graph_names_dup(oi.names, oi.channels);
    if (!sh->names) return 1;
    sh->channels = oi.channels;
    sh->known = 1;
    return 0;
}

/* The evaluation of one frame, run on shapes instead of pixels, in the order internal_graph_eval
 * takes (each write's input, depth first, input 0 first), freeing as the plan frees. A temporal
 * source's frame counts twice: the one before stays while its readers work. */
typedef struct sim {
    nprfx_graph *g;
    int frame;
    shape *shapes;
    int *done, *uses;
    uint64_t live, peak;
    int peak_node, peak_w, peak_h, peak_channels; /* the frame that made the peak */
} sim;

static void sim_note(sim *s, uint64_t transient, int node, int w, int h, int channels)
{
    if (s->live + transient > s->peak) {
        s->peak = s->live + transient;
        s->peak_node = node;
        s->peak_w = w;
        s->peak_h = h;
        s->peak_channels = channels;
    }
}

static void sim_consume(sim *s, int src)
{
    if (--s->uses[src] == 0 && !s->g->plan_temporal[src]) s->live -= shape_bytes(&s->shapes[src]);
}

/* Evaluate node root (and what it needs) on shapes: non-zero when a shape cannot be told. */
static int sim_eval(sim *s, int root)
{
    nprfx_graph *g = s->g;
    int cap = 64, top = 0, rc = 0;
    int *stack = malloc((size_t)cap * 2 * sizeof *stack); /* (node, expanded) pairs */
    if (!stack) return 1;
    stack[0] = root;
    stack[1] = 0;
    top = 1;
    while (top > 0 && !rc) {
        int node = stack[2 * (top - 1)], *expanded = &stack[2 * (top - 1) + 1];
        if (s->done[node]) {
            top--;
            continue;
        }
        const gnode *n = &g->nodes[node];
        if (!*expanded) {
            *expanded = 1;
            for (int k = n->ninputs - 1; k >= 0; k--) {
                int src = n->inputs[k].src;
                if (src < 0 || s->done[src]) continue;
                if (top == cap) {
                    int *grown = realloc(stack, (size_t)cap * 4 * sizeof *stack);
                    if (!grown) {
                        rc = 1;
                        break;
                    }
                    stack = grown;
                    cap *= 2;
                }
                stack[2 * top] = src;
                stack[2 * top + 1] = 0;
                top++;
            }
            continue;
        }
        top--;
        uint64_t scratch = 0;
        int k = shape_of(g, node, s->frame, &s->shapes[node], &scratch);
        if (k < 0) k = node_shape(g, node, s->shapes, &s->shapes[node], &scratch);
        if (k) {
            rc = 1;
            break;
        }
        const shape *sh = &s->shapes[node];
        uint64_t b = shape_bytes(sh);
        s->live += g->plan_temporal[node] ? 2 * b : b;
        sim_note(s, scratch, node, sh->w, sh->h, sh->channels);
        s->done[node] = 1;
        for (int j = 0; j < n->ninputs; j++)
            if (n->inputs[j].src >= 0) sim_consume(s, n->inputs[j].src);
    }
    free(stack);
    return rc;
}

nprfx_result nprfx_graph_plan(nprfx_graph *g, int frame, nprfx_graph_plan_info *out)
{
    memset(out, 0, sizeof *out);
    out->limit = g->mem_limit;
    nprfx_result r = internal_graph_plan_build(g);
    if (r) return r;
    sim s;
    memset(&s, 0, sizeof s);
    s.g = g;
    s.frame = frame;
    s.peak_node = -1;
    s.shapes = calloc((size_t)(g->count ? g->count : 1), sizeof *s.shapes);
    s.done = calloc((size_t)(g->count ? g->count : 1), sizeof *s.done);
    s.uses = malloc((size_t)(g->count ? g->count : 1) * sizeof *s.uses);
    int failed = !s.shapes || !s.done || !s.uses;
    if (!failed) memcpy(s.uses, g->plan_uses, (size_t)g->count * sizeof *s.uses);
    for (int i = 0; !failed && i < g->count; i++) {
        const gnode *w = &g->nodes[i];
        if (w->kind != GK_WRITE || w->inputs[0].src < 0) continue;
        int src = w->inputs[0].src;
        if ((failed = sim_eval(&s, src))) break;
        /* the write packs the channels it writes when they are not adjacent */
        int idx[256], count = 0;
        const shape *sh = &s.shapes[src];
        if (internal_graph_input_channels(g, w, 0, (const char *const *)sh->names, sh->channels,
                                          idx, &count)) {
            failed = 1;
            break;
        }
        sim_note(&s, packed_bytes(sh, idx, count), i, sh->w, sh->h, count);
        sim_consume(&s, src);
    }
    if (!failed && s.peak_node >= 0) {
        shape peak = {s.peak_w, s.peak_h, s.peak_channels, 1, NULL}, *sh = &peak;
        out->peak = s.peak;
        out->width = sh->w;
        out->height = sh->h;
        out->peak_node = g->nodes[s.peak_node].name;
        if (g->mem_limit != UINT64_MAX && s.peak > g->mem_limit) {
            char need[32], lim[32], one[32];
            nprfx_format_bytes(need, sizeof need, s.peak);
            nprfx_format_bytes(lim, sizeof lim, g->mem_limit);
            nprfx_format_bytes(one, sizeof one, shape_bytes(sh));
            r = nprfx_error(
                g->ctx, NPRFX_ERR_OUT_OF_MEMORY,
                "frame %d needs %s of frames at its peak, at node '%s' (its %dx%d frame "
                "with %d channel%s, %s, joins the frames still held): above the %s "
                "memory limit (%s); nothing was rendered",
                frame, need, g->nodes[s.peak_node].name, sh->w, sh->h, sh->channels,
                sh->channels == 1 ? "" : "s", one, lim, nprfx_mem_limit_origin());
        }
    }
    for (int i = 0; s.shapes && i < g->count; i++)
        shape_free(&s.shapes[i]);
    free(s.shapes);
    free(s.done);
    free(s.uses);
    return r;
}
