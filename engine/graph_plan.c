/* nprfx graph engine — the graph's memory plan (docs/design.md §1 "Memory").
 *
 * The cache alone kept every result until its byte bound pushed it out: a graph over 1080p plates
 * held 2 GiB of frames it would never read again. The engine knows the graph, so it plans:
 *  - each result knows how many inputs read it at its frame (plan_uses); when the last of them
 *    has rendered, the result leaves the cache at once and its buffer goes back to the pool;
 *  - a node that some temporal node reads at other frames (what the node declares through
 *    nprfx_node_frames_needed) keeps its results past the frame: after each frame those inside
 *    the window of offsets touched during it, moved on by the step to the next frame, stay, and
 *    the cache's byte bound still caps them;
 *  - a plate keeps only the channels its readers select;
 *  - every frame buffer comes from the frame pool (frame_pool.h) and goes back to it, so a frame
 *    of the same size is not faulted in again;
 *  - every allocation is checked against the memory limit (io_limits.h) before it is made, and
 *    nprfx_graph_plan estimates the peak from the graph and the frame size before frame 1.
 * Results never depend on any of it: a result dropped too early is rendered again, bit for bit
 * (docs/design.md §1, "a cache may save work, never change a result").
 *
 * This file makes the plan (consumer counts, temporal sources) and picks the channels plates
 * keep; graph_frames.c counts the frames held, graph_memory.c hands them out under the limit and
 * frees consumed results, graph_estimate.c is nprfx_graph_plan. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "nprfx/graph.h"
#include "graph_frames.h"
#include "graph_memory.h"
#include "graph_model.h"
#include "graph_extras.h"
#include "graph_plan.h"
#include "graph_resolve.h"
#include "nprfx/channels.h"

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
    free(g->plan_first);
    free(g->plan_readers);
    size_t edges = 0;
    for (int i = 0; i < g->count; i++)
        edges += (size_t)g->nodes[i].ninputs;
    size_t nodes = g->count > 0 ? (size_t)g->count : 1;
    g->plan_uses = calloc(nodes, sizeof *g->plan_uses);
    g->plan_temporal = calloc(nodes, 1);
    g->plan_first = calloc(nodes + 1, sizeof *g->plan_first);
    g->plan_readers = malloc((edges ? edges : 1) * sizeof *g->plan_readers);
    if (!g->plan_uses || !g->plan_temporal || !g->plan_first || !g->plan_readers)
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
    /* readers by source, in graph order: counts, then starts, then fill */
    for (int i = 0; i < g->count; i++)
        g->plan_first[i + 1] = g->plan_first[i] + g->plan_uses[i];
    int *fill = calloc(nodes, sizeof *fill);
    if (!fill) return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory planning");
    for (int i = 0; i < g->count; i++)
        for (int k = 0; k < g->nodes[i].ninputs; k++) {
            int src = g->nodes[i].inputs[k].src;
            if (src < 0) continue;
            int at = g->plan_first[src] + fill[src]++;
            g->plan_readers[at][0] = i;
            g->plan_readers[at][1] = k;
        }
    free(fill);
    g->plan_ready = 1;
    return NPRFX_OK;
}

int internal_graph_plate_channels(nprfx_graph *g, int node, const char *const *names, int nc,
                                  unsigned char *keep)
{
    if (!g->plan_ready || g->no_pool || g->external) return -1;
    memset(keep, 0, (size_t)nc);
    int kept = 0;
    for (int r = g->plan_first[node]; r < g->plan_first[node + 1]; r++) {
        int idx[256], count = 0;
        const gnode *reader = &g->nodes[g->plan_readers[r][0]];
        if (internal_graph_input_channels(g, reader, g->plan_readers[r][1], names, nc, idx, &count))
            return -1;
        for (int c = 0; c < count; c++)
            if (idx[c] >= 0 && idx[c] < nc && !keep[idx[c]]) {
                keep[idx[c]] = 1;
                kept++;
            }
    }
    return kept;
}

/* Whether input k of reader selects from names (nc) the channels that `whole` (nw) gives it,
 * through map (index in names -> index in whole). */
static int same_selection(nprfx_graph *g, const gnode *reader, int k, const char *const *whole,
                          int nw, const char *const *names, int nc, const int *map)
{
    int a[256], b[256], ca = 0, cb = 0;
    if (internal_graph_input_channels(g, reader, k, whole, nw, a, &ca) ||
        internal_graph_input_channels(g, reader, k, names, nc, b, &cb) || ca != cb)
        return 0;
    for (int c = 0; c < ca; c++)
        if (map[b[c]] != a[c]) return 0;
    return 1;
}

/* Whether `sel` picks from names (nc) the channels it picks from whole (nw), through map. */
static int same_pick(const char *sel, const char *const *whole, int nw, const char *const *names,
                     int nc, const int *map)
{
    int a[8], b[8], amb;
    char bad[64];
    int ca = nprfx_channels_select(whole, nw, sel, a, 8, bad, sizeof bad, &amb);
    int cb = nprfx_channels_select(names, nc, sel, b, 8, bad, sizeof bad, &amb);
    if (ca != cb) return 0;
    for (int c = 0; c < ca; c++)
        if (map[b[c]] != a[c]) return 0;
    return 1;
}

/* Whether the extras made from channels `sub` (through map) come from the channels they come from
 * in the whole plate. */
static int same_extras(const gextra *whole, const gextra *sub, const int *map)
{
    if (whole->count != sub->count) return 0;
    for (int k = 0; k < whole->count; k++)
        for (int j = 0; j < 2; j++)
            if ((whole->src[k][j] < 0) != (sub->src[k][j] < 0) ||
                (sub->src[k][j] >= 0 && map[sub->src[k][j]] != whole->src[k][j]))
                return 0;
    return 1;
}

int internal_graph_read_pick(nprfx_graph *g, int node, const char *const *names, int nc, int *pick)
{
    const gnode *n = &g->nodes[node];
    int extra = internal_graph_extra_count(n);
    if (nc < 1 || nc + extra > 1024) return -1; /* wider plates are read whole */
    const char *all[1024], *sub[1024];
    unsigned char keep[1024];
    int map[1024];
    for (int c = 0; c < nc; c++)
        all[c] = names[c];
    for (int k = 0; k < extra; k++)
        all[nc + k] = internal_graph_extra_name(n, k);
    int na = nc + extra;
    if (internal_graph_plate_channels(g, node, all, na, keep) <= 0) return -1;
    /* What the read makes of its plate needs its sources: the channels the appended channels are
     * made of (the read fails without them), and R,G,B when it converts colour (OCIO may mix
     * them), so the channels read are converted exactly as in the whole plate. */
    int rgb[3], amb;
    char bad[64];
    gextra xw, xs;
    if (extra && internal_graph_extras(g, n, "", names, nc, &xw)) return -1;
    for (int k = 0; extra && k < xw.count; k++)
        for (int j = 0; j < 2; j++)
            if (xw.src[k][j] >= 0) keep[xw.src[k][j]] = 1;
    int have_rgb = internal_graph_colorspace(n) &&
                   nprfx_channels_select(all, na, "R,G,B", rgb, 3, bad, sizeof bad, &amb) == 3;
    for (int c = 0; have_rgb && c < 3; c++)
        keep[rgb[c]] = 1;
    int m = 0;
    for (int c = 0; c < nc; c++)
        if (keep[c]) {
            map[m] = c;
            sub[m] = names[c];
            pick[m++] = c;
        }
    if (m == nc) return -1;
    for (int k = 0; k < extra; k++) {
        map[m + k] = nc + k;
        sub[m + k] = all[nc + k];
    }
    /* Every choice made on the plate must come out the same on the channels read (a suffix
     * ambiguous in the whole plate could become unique); else the whole plate is read. */
    for (int r = g->plan_first[node]; r < g->plan_first[node + 1]; r++)
        if (!same_selection(g, &g->nodes[g->plan_readers[r][0]], g->plan_readers[r][1], all, na,
                            sub, m + extra, map))
            return -1;
    if (extra && (internal_graph_extras(g, n, "", sub, m, &xs) || !same_extras(&xw, &xs, map)))
        return -1;
    if (internal_graph_colorspace(n) && !same_pick("R,G,B", all, na, sub, m + extra, map))
        return -1;
    return m;
}

int internal_graph_plate_pick(nprfx_graph *g, int node, const char *const *names, int nc, int *map)
{
    unsigned char keep[1024]; /* wider plates stay whole */
    if (nc > (int)sizeof keep) return 0;
    int kept = internal_graph_plate_channels(g, node, names, nc, keep);
    if (kept <= 0 || kept == nc) return 0;
    /* Each reader must select the same channels from the trimmed plate as from the whole one (a
     * suffix that was ambiguous could otherwise become unique); else the plate stays whole. */
    const char *sub[1024];
    int n = 0;
    for (int c = 0; c < nc; c++)
        if (keep[c]) {
            map[n] = c;
            sub[n++] = names[c];
        }
    for (int r = g->plan_first[node]; r < g->plan_first[node + 1]; r++)
        if (!same_selection(g, &g->nodes[g->plan_readers[r][0]], g->plan_readers[r][1], names, nc,
                            sub, kept, map))
            return 0;
    return kept;
}

int internal_graph_trim_plate(nprfx_graph *g, int node, nprfx_image *im, char ***names, gmeta *meta,
                              int pooled)
{
    int nc = im->channels, map[1024];
    int kept = internal_graph_plate_pick(g, node, (const char *const *)*names, nc, map);
    if (kept <= 0) return 0;
    char **sub = calloc((size_t)kept, sizeof *sub);
    if (!sub) return 0;
    for (int c = 0; c < kept; c++)
        sub[c] = (*names)[map[c]];
    char what[600];
    snprintf(what, sizeof what, "node '%s': the %d channels its readers take", g->nodes[node].name,
             kept);
    nprfx_image t;
    if (internal_graph_frame_alloc(g, node, what, im->bounds, kept, &t)) {
        free(sub); /* whole, as before: the limit is checked again where it matters */
        return 0;
    }
    for (int y = t.bounds.y0; y < t.bounds.y1; y++)
        for (int x = t.bounds.x0; x < t.bounds.x1; x++) {
            const float *s = nprfx_image_at(im, x, y);
            float *d = nprfx_image_at(&t, x, y);
            for (int c = 0; c < kept; c++)
                d[c] = s[map[c]];
        }
    for (int c = 0, m = 0; c < nc; c++) /* map is increasing */
        if (m < kept && map[m] == c)
            m++;
        else
            free((*names)[c]);
    free(*names);
    *names = sub;
    /* Whatever is kept per channel follows the same map, so a plate written as read still
     * writes each channel with its file type (map[c] >= c: compacted in place). */
    if (meta && meta->types)
        for (int c = 0; c < kept; c++)
            meta->types[c] = meta->types[map[c]];
    /* A pool frame (synth, a read by rows) goes back to the pool: the next frame's plate takes
     * it without faulting its pages in again. A reader's own plate goes back to the system: the
     * reader allocates its own, so idle in the pool it would only hold the memory the trim
     * saves. */
    if (pooled) {
        internal_graph_frame_release(g, im);
    } else {
        size_t bytes = internal_graph_image_bytes(im);
        g->held_bytes -= bytes < g->held_bytes ? bytes : g->held_bytes;
        nprfx_image_free(im);
    }
    *im = t;
    return 1;
}
