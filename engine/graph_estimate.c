/* nprfx graph engine — nprfx_graph_plan: the memory a frame needs, estimated before frame 1 from
 * the graph and the frames' sizes alone (plates' headers, synth sizes, "format"), by running the
 * memory plan on shapes instead of pixels; strips when whole frames would pass the limit. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "nprfx/graph.h"
#include "graph_frames.h"
#include "graph_extras.h"
#include "graph_model.h"
#include "graph_scale.h"
#include "graph_plan.h"
#include "graph_resolve.h"
#include "graph_strips.h"
#include "nprfx/io.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "nprfx/io.h"
#include "engine_util.h"

/* One node's frame in the estimate: its size, channels and their names. */
typedef struct shape {
    int w, h, channels, known;
    char **names; /* owned, channels of them */
} shape;

static void shape_free(shape *s)
{
    engine_names_free(s->names, s->channels);
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
        /* internal_graph_synth_plate renders only the channels its readers take: no whole plate to
         * hold */
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
        if (g->io.info(g->ctx, file, &info)) return 1;
        int extra = internal_graph_extra_count(n);
        /* The read delivers only the channels it picks (internal_graph_read_plate), then appends
         * its own (graph_extras.c); the trim drops what only those were read for. */
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
            sh->names[c] = engine_strdup(info.names[pick[c]]);
        for (int c = 0; sh->names && c < extra; c++)
            sh->names[nread + c] = engine_strdup(internal_graph_extra_name(n, c));
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
    nprfx_value scaled[64];
    const nprfx_value *params = n->params;
    if (n->desc->num_params <= 64) /* the plate's width stands for its display window's */
        params = internal_graph_scale_params(
            n, params, internal_graph_param_scale(g, nprfx_rect_make(0, 0, sh->w, sh->h)), scaled);
    return internal_graph_query_state(g, n, params, sh->w, sh->h, in_ch);
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
                       nprfx_memory_limit_origin(g->ctx));
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
                sh->channels == 1 ? "" : "s", one, lim, nprfx_memory_limit_origin(g->ctx),
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
