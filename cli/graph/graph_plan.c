/* nprfx CLI — the graph's memory plan (docs/design.md §1 "Memory").
 *
 * The cache alone kept every result until its byte bound pushed it out: a graph over 1080p plates
 * held 2 GiB of frames it would never read again. The runner knows the graph, so it plans:
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
 * (docs/design.md §1, "a cache may save work, never change a result"). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/channels.h"
#include "internal_graph.h"
#include "io/io.h"
#include "io/io_limits.h"
#include "nprfx/synth.h"
#include "util/cli_util.h"

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

static size_t image_bytes(const nprfx_image *im);

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

int internal_graph_read_pick(nprfx_graph *g, int node, const char *const *names, int nc, int *pick)
{
    const gnode *n = &g->nodes[node];
    int motion = n->vectors && strcmp(n->vectors, "none") ? 4 : 0;
    if (nc < 1 || nc + motion > 1024) return -1; /* wider plates are read whole */
    const char *all[1024], *sub[1024];
    unsigned char keep[1024];
    int map[1024];
    for (int c = 0; c < nc; c++)
        all[c] = names[c];
    for (int k = 0; k < motion; k++)
        all[nc + k] = internal_graph_motion_names[k];
    int na = nc + motion;
    if (internal_graph_plate_channels(g, node, all, na, keep) <= 0) return -1;
    /* What the read makes of its plate needs its sources: the channels the motion channels are
     * made of (the read fails without them), and R,G,B when it converts colour (OCIO may mix
     * them), so the channels read are converted exactly as in the whole plate. */
    int src[4] = {0}, rgb[3], amb;
    double sign[4];
    char bad[64];
    if (motion && internal_graph_motion_sources(g, n, "", names, nc, src, sign)) return -1;
    for (int k = 0; k < motion; k++)
        keep[src[k]] = 1;
    int have_rgb = n->colorspace &&
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
    for (int k = 0; k < motion; k++) {
        map[m + k] = nc + k;
        sub[m + k] = all[nc + k];
    }
    /* Every choice made on the plate must come out the same on the channels read (a suffix
     * ambiguous in the whole plate could become unique); else the whole plate is read. */
    for (int r = g->plan_first[node]; r < g->plan_first[node + 1]; r++)
        if (!same_selection(g, &g->nodes[g->plan_readers[r][0]], g->plan_readers[r][1], all, na,
                            sub, m + motion, map))
            return -1;
    int sub_src[4];
    if (motion && internal_graph_motion_sources(g, n, "", sub, m, sub_src, sign)) return -1;
    for (int k = 0; k < motion; k++)
        if (map[sub_src[k]] != src[k]) return -1;
    if (n->colorspace && !same_pick("R,G,B", all, na, sub, m + motion, map)) return -1;
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

int internal_graph_trim_plate(nprfx_graph *g, int node, nprfx_image *im, char ***names, gmeta *meta)
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
    /* A synth frame goes back to the pool: the next frame's synth takes it without faulting
     * its pages in again. A reader's plate goes back to the system: the reader allocates its
     * own, so idle in the pool it would only hold the memory the trim saves. */
    if (g->nodes[node].kind == GK_SYNTH) {
        internal_graph_frame_release(g, im);
    } else {
        size_t bytes = image_bytes(im);
        g->held_bytes -= bytes < g->held_bytes ? bytes : g->held_bytes;
        nprfx_image_free(im);
    }
    *im = t;
    return 1;
}

static size_t image_bytes(const nprfx_image *im)
{
    return (size_t)nprfx_rect_width(im->bounds) * (size_t)nprfx_rect_height(im->bounds) *
           (size_t)im->channels * sizeof(float);
}

static void note_peak(nprfx_graph *g)
{
    size_t now = g->held_bytes + g->state_bytes + nprfx_frame_pool_idle_bytes(g->pool);
    if (now > g->mem_peak) g->mem_peak = now;
}

/* The bytes node n keeps between the graph's frames of w x h, its inputs selecting in_ch
 * channels (desc->state_bytes); 0 when it cannot be told (the render reports why). */
static uint64_t query_state(nprfx_graph *g, const gnode *n, const nprfx_value *params, int w, int h,
                            const int *in_ch)
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
    g->state_bytes += (size_t)query_state(g, n, params, w, h, in_ch);
    note_peak(g);
}

/* Make room for `bytes` more under the limit, beside the caches nodes keep: the pool's idle
 * buffers first, then unpinned results, least recently used first. Whether it fits now. */
static int make_room(nprfx_graph *g, size_t bytes)
{
    if (g->mem_limit == UINT64_MAX) return 1;
    size_t kept = g->state_bytes;
    if (g->held_bytes + kept + nprfx_frame_pool_idle_bytes(g->pool) + bytes <= g->mem_limit)
        return 1;
    nprfx_frame_pool_trim(g->pool, 0);
    for (centry *e = g->tail, *prev; e && g->held_bytes + kept + bytes > g->mem_limit; e = prev) {
        prev = e->prev;
        if (!e->pins) internal_graph_cache_drop(g, e);
    }
    return g->held_bytes + kept + bytes <= g->mem_limit;
}

static nprfx_result frame_alloc(nprfx_graph *g, int node, const char *what, nprfx_rect bounds,
                                int channels, int clear, nprfx_image *im)
{
    int w = nprfx_rect_width(bounds), h = nprfx_rect_height(bounds);
    nprfx_result r = nprfx_image_limit_check(g->ctx, what, w, h, channels, 0);
    if (r) return r;
    size_t bytes = (size_t)w * (size_t)h * (size_t)(channels > 0 ? channels : 0) * sizeof(float);
    if (!make_room(g, bytes)) {
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
                           nprfx_mem_limit_origin());
    }
    int reused = 0;
    if ((r = nprfx_frame_pool_alloc(g->pool, g->ctx, bounds, channels, clear, im, &reused)))
        return r;
    g->held_bytes += bytes;
    if (node >= 0 && node < g->count) {
        g->stats[node].bytes += bytes;
        if (!reused) g->stats[node].fresh_bytes += bytes;
    }
    note_peak(g);
    return NPRFX_OK;
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
    nprfx_frame_pool_age(g->pool);
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
            char *s = cli_strdup(scene);
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
        char *s = cli_strdup(buf);
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

/* The shape of plate node i at frame; -1 for a processing node (node_shape); non-zero when it
 * cannot be told without rendering (the render then reports whatever is wrong). */
/* What internal_graph_trim_plate keeps of a plate's shape; *scratch gets the whole plate's
 * bytes when it is trimmed (held until the trim is made). */
static void trim_shape(nprfx_graph *g, int node, shape *sh, uint64_t *scratch)
{
    unsigned char keep[1024];
    if (sh->channels > 1024) return;
    int kept =
        internal_graph_plate_channels(g, node, (const char *const *)sh->names, sh->channels, keep);
    if (kept <= 0 || kept == sh->channels) return;
    *scratch = shape_bytes(sh);
    int n = 0;
    for (int c = 0; c < sh->channels; c++) {
        if (keep[c])
            sh->names[n++] = sh->names[c];
        else
            free(sh->names[c]);
    }
    sh->channels = n;
}

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
        /* eval_synth renders only the channels its readers take: no whole plate to hold */
        int map[1024];
        int kept = internal_graph_plate_pick(g, i, (const char *const *)sh->names, nc, map);
        if (kept > 0) {
            unsigned char keep[1024] = {0};
            for (int c = 0; c < kept; c++)
                keep[map[c]] = 1;
            int m = 0;
            for (int c = 0; c < nc; c++) { /* map is increasing: compacted in place */
                if (keep[c])
                    sh->names[m++] = sh->names[c];
                else
                    free(sh->names[c]);
            }
            sh->channels = kept;
        }
        return 0;
    }
    if (n->kind == GK_READ) {
        char file[4096];
        internal_graph_resolve_path(g, g->base_dir, n->path, frame, file, sizeof file);
        nprfx_file_info info;
        memset(&info, 0, sizeof info);
        if (nprfx_io_info(g->ctx, file, &info)) return 1;
        int extra = n->vectors && strcmp(n->vectors, "none") ? 4 : 0;
        /* The read delivers only the channels it picks (eval_read), then appends the motion
         * channels; the trim drops what only those were read for. */
        int pick[1024], nread = info.nchannels;
        int m = info.nchannels <= 1024
                    ? internal_graph_read_pick(g, i, (const char *const *)info.names,
                                               info.nchannels, pick)
                    : -1;
        if (m > 0)
            nread = m;
        else
            for (int c = 0; c < nread; c++)
                pick[c] = c;
        sh->names = calloc((size_t)(nread + extra), sizeof *sh->names);
        for (int c = 0; sh->names && c < nread; c++)
            sh->names[c] = cli_strdup(info.names[pick[c]]);
        for (int c = 0; sh->names && c < extra; c++)
            sh->names[nread + c] = cli_strdup(internal_graph_motion_names[c]);
        sh->w = nprfx_rect_width(info.bounds);
        sh->h = nprfx_rect_height(info.bounds);
        sh->channels = nread + extra;
        nprfx_file_info_free(&info);
        if (!sh->names) return 1;
        sh->known = 1;
        trim_shape(g, i, sh, scratch);
        return 0;
    }
    return -1; /* processing nodes: by the caller, which has the inputs' shapes */
}

/* The bytes of the channels (idx, count of them) an input (flags) packs out of its source: 0
 * when it reads them in place. */
static uint64_t packed_bytes(const shape *src, const int *idx, int count, unsigned flags)
{
    if (!internal_graph_packs(src->channels, idx, count, flags)) return 0;
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
        *scratch += packed_bytes(s, idx, count, d->inputs[k].flags);
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

/* Two frames of the evaluation, run on shapes instead of pixels, in the order internal_graph_eval
 * takes (each write's input, depth first, input 0 first), holding and freeing as the plan does:
 * a frame goes to the pool's idle list when its last reader has rendered, is taken from it by the
 * next frame of the same size, and a temporal source's frame stays until the sweep after the next
 * frame. The second frame is the steady state: the first frame's buffers wait idle in the pool. */
typedef struct sim {
    nprfx_graph *g;
    int frame;
    shape *shapes;
    uint64_t *scratch;    /* per node: input channels packed, or a whole plate before its trim */
    uint64_t *cur, *prev; /* per node: bytes its result holds at this frame, the one before */
    int *done, *uses;
    uint64_t *idle; /* the pool's idle buffers, by size */
    size_t nidle, capidle;
    uint64_t live, idle_bytes, peak, need; /* peak: with the pool's idle buffers; need: without */
    int peak_node, peak_w, peak_h, peak_channels; /* the frame that made the need's peak */
    unsigned char *stated;                        /* per node: its state is counted */
    uint64_t state; /* the bytes stateful nodes keep between frames, all of them */
} sim;

static void sim_note(sim *s, int node, int w, int h, int channels)
{
    if (s->live + s->idle_bytes > s->peak) s->peak = s->live + s->idle_bytes;
    /* Idle buffers only save page faults: under the limit the render gives them up
     * (make_room), so only the frames in use decide whether the graph fits. */
    if (s->live > s->need) {
        s->need = s->live;
        s->peak_node = node;
        s->peak_w = w;
        s->peak_h = h;
        s->peak_channels = channels;
    }
}

/* A pooled allocation: an idle buffer of the size when there is one. */
static void sim_alloc(sim *s, uint64_t bytes)
{
    for (size_t i = 0; i < s->nidle; i++)
        if (s->idle[i] == bytes) {
            s->idle[i] = s->idle[--s->nidle];
            s->idle_bytes -= bytes;
            break;
        }
    s->live += bytes;
}

static int sim_release(sim *s, uint64_t bytes)
{
    if (!bytes) return 0;
    s->live -= bytes;
    if (s->nidle == s->capidle) {
        size_t n = s->capidle ? 2 * s->capidle : 64;
        uint64_t *grown = realloc(s->idle, n * sizeof *grown);
        if (!grown) return 1;
        s->idle = grown;
        s->capidle = n;
    }
    s->idle[s->nidle++] = bytes;
    s->idle_bytes += bytes;
    return 0;
}

static int sim_consume(sim *s, int src)
{
    if (--s->uses[src] != 0 || s->g->plan_temporal[src]) return 0;
    uint64_t b = s->cur[src];
    s->cur[src] = 0;
    return sim_release(s, b);
}

/* The bytes node n keeps in its state between frames of shape sh (desc->state_bytes), its
 * inputs' channel counts from their shapes; 0 when it cannot be told (the render reports why). */
static uint64_t state_bytes(nprfx_graph *g, const gnode *n, const shape *shapes, const shape *sh)
{
    int in_ch[32] = {0};
    if (n->desc->num_inputs > 32) return 0;
    for (int k = 0; k < n->desc->num_inputs; k++) {
        int src = n->inputs[k].src, idx[256];
        if (src < 0 || !shapes[src].known) continue;
        if (internal_graph_input_channels(g, n, k, (const char *const *)shapes[src].names,
                                          shapes[src].channels, idx, &in_ch[k]))
            return 0;
    }
    return query_state(g, n, n->params, sh->w, sh->h, in_ch);
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
        shape *sh = &s->shapes[node];
        if (!sh->known) {
            int k = shape_of(g, node, s->frame, sh, &s->scratch[node]);
            if (k < 0) k = node_shape(g, node, s->shapes, sh, &s->scratch[node]);
            if (k) {
                rc = 1;
                break;
            }
        }
        uint64_t b = shape_bytes(sh), extra = s->scratch[node];
        int plate = n->kind == GK_READ || n->kind == GK_SYNTH;
        /* the plate as made (a read's picked channels, a synth's all), then its trim
         * (internal_graph_trim_plate) */
        if (plate && extra) {
            if (n->kind == GK_SYNTH)
                sim_alloc(s, extra);
            else
                s->live += extra;
            sim_alloc(s, b);
            sim_note(s, node, sh->w, sh->h, sh->channels);
            if (n->kind == GK_SYNTH)
                rc |= sim_release(s, extra);
            else
                s->live -= extra;
        } else {
            if (extra) sim_alloc(s, extra); /* the inputs' packed channels */
            if (n->kind == GK_READ)
                s->live += b;
            else
                sim_alloc(s, b);
            sim_note(s, node, sh->w, sh->h, sh->channels);
            if (extra) rc |= sim_release(s, extra);
        }
        /* a stateful node's caches, from its first render on, for good */
        if (n->kind == GK_NODE && (n->desc->flags & NPRFX_NODE_STATEFUL) && !s->stated[node]) {
            s->stated[node] = 1;
            uint64_t kept = state_bytes(g, n, s->shapes, sh);
            s->state += kept;
            s->live += kept;
            sim_note(s, node, sh->w, sh->h, sh->channels);
        }
        s->cur[node] = b;
        s->done[node] = 1;
        for (int j = 0; j < n->ninputs; j++)
            if (n->inputs[j].src >= 0) rc |= sim_consume(s, n->inputs[j].src);
    }
    free(stack);
    return rc;
}

/* One frame of the simulation: every write's input, then the sweep. */
static int sim_frame(sim *s)
{
    nprfx_graph *g = s->g;
    memset(s->done, 0, (size_t)g->count * sizeof *s->done);
    memcpy(s->uses, g->plan_uses, (size_t)g->count * sizeof *s->uses);
    for (int i = 0; i < g->count; i++) {
        const gnode *w = &g->nodes[i];
        if (w->kind != GK_WRITE || w->inputs[0].src < 0) continue;
        int src = w->inputs[0].src;
        if (sim_eval(s, src)) return 1;
        /* the write packs the channels it writes when they are not adjacent */
        int idx[256], count = 0;
        const shape *sh = &s->shapes[src];
        if (internal_graph_input_channels(g, w, 0, (const char *const *)sh->names, sh->channels,
                                          idx, &count))
            return 1;
        uint64_t pack = packed_bytes(sh, idx, count, 0u);
        sim_alloc(s, pack);
        sim_note(s, i, sh->w, sh->h, count);
        if (sim_release(s, pack) || sim_consume(s, src)) return 1;
    }
    for (int i = 0; i < g->count; i++) { /* the sweep: a temporal source keeps this frame */
        if (sim_release(s, s->prev[i])) return 1;
        s->prev[i] = 0;
        if (g->plan_temporal[i])
            s->prev[i] = s->cur[i];
        else if (sim_release(s, s->cur[i]))
            return 1;
        s->cur[i] = 0;
    }
    return 0;
}

/* Rows per strip when the plan chooses strips itself (a graph over the memory limit): a few
 * chunks of most EXR compressions, small against any frame worth striping. */
#define PLAN_STRIP_ROWS 64

/* Strips (graph_strips.c) instead of whole frames: always with --strip-rows N, and when whole
 * frames would pass the limit (over) and every write can render by rows. out->need becomes what
 * the strips hold; a limit even strips pass is refused here. Otherwise why says what keeps the
 * graph from strips (for the whole-frame refusal). */
static nprfx_result plan_strips(nprfx_graph *g, int frame, int over, nprfx_graph_plan_info *out,
                                char *why, size_t n)
{
    g->strip_rows = g->strip_option > 0 ? g->strip_option : 0;
    if (g->strip_option < 0 || (g->strip_option == 0 && !over) || g->no_pool) return NPRFX_OK;
    int rows = g->strip_option > 0 ? g->strip_option : PLAN_STRIP_ROWS;
    uint64_t need = 0;
    int writer = -1, writes = 0, all = 1;
    for (int i = 0; i < g->count; i++) {
        if (g->nodes[i].kind != GK_WRITE) continue;
        writes++;
        if (!internal_graph_strips_possible(g, i, why, n)) {
            all = 0;
            continue;
        }
        nprfx_result err = NPRFX_OK;
        uint64_t b = internal_graph_strip_need(g, i, frame, rows, &err);
        /* A plate's block above the limit: even strips do not fit (the message says so). Any
         * other problem: whole frames, and the render reports it. */
        if (err == NPRFX_ERR_OUT_OF_MEMORY) {
            char why_strips[1024], wb[32];
            nprfx_context_last_error(g->ctx, why_strips, sizeof why_strips);
            nprfx_format_bytes(wb, sizeof wb, out->whole_need);
            g->strip_rows = 0;
            return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY,
                               "frame %d needs %s of frames whole, and strips of %d rows do not "
                               "fit either: %s; nothing was rendered",
                               frame, wb, rows, why_strips);
        }
        if (err) {
            g->strip_rows = g->strip_option > 0 ? g->strip_option : 0;
            return NPRFX_OK;
        }
        if (b > need) {
            need = b;
            writer = i;
        }
    }
    /* Some writes whole, some by strips: only with --strip-rows, and the whole-frame estimate
     * (all writes) stands. */
    if (!writes || (!all && g->strip_option == 0)) return NPRFX_OK;
    if (!all) {
        g->strip_rows = rows;
        return NPRFX_OK;
    }
    need += out->state; /* the stateful nodes' caches, besides the strips */
    g->strip_rows = rows;
    out->strip_rows = rows;
    out->need = need;
    out->peak = need;
    out->peak_node = writer >= 0 ? g->nodes[writer].name : out->peak_node;
    if (g->mem_limit == UINT64_MAX || need <= g->mem_limit) return NPRFX_OK;
    g->strip_rows = 0;
    char nb[32], wb[32], lim[32];
    nprfx_format_bytes(nb, sizeof nb, need);
    nprfx_format_bytes(wb, sizeof wb, out->whole_need);
    nprfx_format_bytes(lim, sizeof lim, g->mem_limit);
    return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY,
                       "frame %d needs %s of frames whole, and still %s in strips of %d rows "
                       "(write node '%s' and the nodes it reads, %dx%d): above the %s memory "
                       "limit (%s); nothing was rendered (fewer rows: --strip-rows)",
                       frame, wb, nb, rows, g->nodes[writer].name, out->width, out->height, lim,
                       nprfx_mem_limit_origin());
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
    size_t nodes = g->count > 0 ? (size_t)g->count : 1;
    s.shapes = calloc(nodes, sizeof *s.shapes);
    s.scratch = calloc(nodes, sizeof *s.scratch);
    s.cur = calloc(nodes, sizeof *s.cur);
    s.prev = calloc(nodes, sizeof *s.prev);
    s.done = calloc(nodes, sizeof *s.done);
    s.uses = calloc(nodes, sizeof *s.uses);
    s.stated = calloc(nodes, 1);
    int failed = !s.shapes || !s.scratch || !s.cur || !s.prev || !s.done || !s.uses || !s.stated;
    for (int f = 0; f < 2 && !failed; f++)
        failed = sim_frame(&s);
    if (!failed && s.peak_node >= 0) {
        shape peak = {s.peak_w, s.peak_h, s.peak_channels, 1, NULL}, *sh = &peak;
        out->peak = s.peak;
        out->need = s.need;
        out->width = sh->w;
        out->height = sh->h;
        out->peak_node = g->nodes[s.peak_node].name;
        out->whole_need = s.need;
        out->state = s.state;
        int over = g->mem_limit != UINT64_MAX && s.need > g->mem_limit;
        char why[600] = "";
        r = plan_strips(g, frame, over, out, why, sizeof why);
        if (r || out->strip_rows > 0) {
            over = 0; /* strips decided, or refused with their own message */
        } else if (over) {
            char need[32], lim[32], one[32], kept[96] = "";
            nprfx_format_bytes(need, sizeof need, s.need);
            if (s.state) {
                char sb[32];
                nprfx_format_bytes(sb, sizeof sb, s.state);
                snprintf(kept, sizeof kept, " (%s of it the caches nodes keep between frames)", sb);
            }
            nprfx_format_bytes(lim, sizeof lim, g->mem_limit);
            nprfx_format_bytes(one, sizeof one, shape_bytes(sh));
            r = nprfx_error(
                g->ctx, NPRFX_ERR_OUT_OF_MEMORY,
                "frame %d needs %s of frames%s at its peak, at node '%s' (its %dx%d frame "
                "with %d channel%s, %s, joins the frames still held): above the %s "
                "memory limit (%s); nothing was rendered%s%s%s",
                frame, need, kept, g->nodes[s.peak_node].name, sh->w, sh->h, sh->channels,
                sh->channels == 1 ? "" : "s", one, lim, nprfx_mem_limit_origin(),
                why[0] ? " (nor can it render by strips of rows: " : "", why, why[0] ? ")" : "");
        }
    }
    for (int i = 0; s.shapes && i < g->count; i++)
        shape_free(&s.shapes[i]);
    free(s.shapes);
    free(s.scratch);
    free(s.cur);
    free(s.prev);
    free(s.done);
    free(s.stated);
    free(s.uses);
    free(s.idle);
    return r;
}
