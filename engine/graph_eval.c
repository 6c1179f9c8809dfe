/* nprfx graph engine — graph evaluation: a node's result at a frame, from the cache or rendered,
 * its inputs evaluated first on an explicit work stack; processing nodes run through
 * nprfx_node_render (or the render hook), temporal inputs fetched through the cache and pinned
 * while a render call uses them. */
#define _DEFAULT_SOURCE
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "nprfx/graph.h"
#include "graph_cache.h"
#include "graph_eval.h"
#include "graph_scale.h"
#include "graph_frames.h"
#include "graph_memory.h"
#include "graph_model.h"
#include "graph_plan.h"
#include "graph_read.h"
#include "graph_resolve.h"
#include "graph_variant.h"
#include "engine_util.h"

/* Packing channels out of a plate, rows [begin, end): a frame's worth of strided reads per
 * input, on every thread (it ran on the evaluating thread alone, pixel by pixel). */
typedef struct pack_job {
    const nprfx_image *src;
    const nprfx_image *dst;
    const int *idx;
    int count;
} pack_job;

static void pack_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const pack_job *pj = user;
    const nprfx_image *d = pj->dst;
    int w = nprfx_rect_width(d->bounds), nc = pj->count;
    ptrdiff_t ps = pj->src->pixel_stride;
    for (int y = d->bounds.y0 + begin; y < d->bounds.y0 + end; y++) {
        const float *s = nprfx_image_at(pj->src, d->bounds.x0, y);
        float *o = nprfx_image_at(d, d->bounds.x0, y);
        if (nc == 1) {
            const float *s0 = s + pj->idx[0];
            for (int x = 0; x < w; x++)
                o[x] = s0[x * ps];
            continue;
        }
        for (int x = 0; x < w; x++, s += ps, o += nc)
            for (int c = 0; c < nc; c++)
                o[c] = s[pj->idx[c]];
    }
}

/* Pick the channels of entry e that input k of node n uses; the view shares e's pixels when
 * they are adjacent, else is *scratch (a frame of the graph's, the caller releases it). */
nprfx_result internal_graph_select_input(nprfx_graph *g, const gnode *n, int k, const centry *e,
                                         nprfx_image *view, nprfx_image *scratch)
{
    int nc = e->im.channels, idx[256], count = 0;
    nprfx_result r =
        internal_graph_input_channels(g, n, k, (const char *const *)e->names, nc, idx, &count);
    if (r) return r;
    unsigned flags = n->kind == GK_NODE ? n->desc->inputs[k].flags : 0u;
    if (!internal_graph_packs(nc, idx, count, flags)) {
        *view = nprfx_image_channels(&e->im, idx[0], count);
        return NPRFX_OK;
    }
    nprfx_image tmp;
    char what[600];
    snprintf(what, sizeof what, "node '%s': input '%s' (channels from '%s')", n->name,
             n->kind == GK_NODE ? n->desc->inputs[k].name : "image", g->nodes[e->node].name);
    /* pack_rows sets every pixel */
    r = internal_graph_frame_alloc_unset(g, (int)(n - g->nodes), what, e->im.bounds, count, &tmp);
    if (r) return r;
    pack_job pj = {&e->im, &tmp, idx, count};
    nprfx_parallel_for(nprfx_context_executor(g->ctx), nprfx_rect_height(tmp.bounds), 16, pack_rows,
                       &pj);
    *scratch = tmp;
    *view = tmp;
    return NPRFX_OK;
}

/* Per-render bookkeeping. The node's own inputs at the current frame stay pinned for the whole
 * render call; frames it fetches go into a ring of NPRFX_FETCH_KEEP * 2 slots, so a long
 * recursion can fetch any number of frames while the most recent ones stay valid. */
typedef struct pin_slot {
    centry *e;
    nprfx_image scratch;
} pin_slot;
#define RING (NPRFX_FETCH_KEEP * 2)
typedef struct render_frame {
    nprfx_graph *g;
    int node;
    pin_slot base[32];
    int nbase;
    pin_slot ring[RING];
    long nfetch;
    /* Warm-up progress (g->progress): the frames the render reads (nprfx_node_frames_needed
     * over all inputs), when it started, when a line last went out. */
    int frame, warm_first, warm_last;
    double t0, last_report;
} render_frame;

/* A render that walks many other frames (coherent-noise's recursion from its start) can take
 * minutes inside one call, with the frame counter standing still: say where it is, once it has
 * taken a second, about once a second. */
#define WARMUP_REPORT_AFTER_S 1.0
static void warmup_progress(render_frame *rf, int fetched)
{
    nprfx_graph *g = rf->g;
    if (!g->progress || fetched == rf->frame || rf->warm_last <= rf->warm_first) return;
    double now = engine_now();
    if (now - rf->t0 < WARMUP_REPORT_AFTER_S || now - rf->last_report < 1.0) return;
    rf->last_report = now;
    const gnode *n = &g->nodes[rf->node];
    long total = (long)rf->warm_last - rf->warm_first + 1;
    long k = fetched < rf->warm_first  ? 0
             : fetched > rf->warm_last ? total
                                       : (long)fetched - rf->warm_first + 1;
    /* backward passes walk down from the last frame: count from there */
    if (fetched > rf->frame) k = (long)rf->warm_last - fetched + 1;
    fprintf(stderr, "%s '%s': frame %d: warming up frames %d-%d (%ld/%ld)\n", n->desc->id, n->name,
            rf->frame, rf->warm_first, rf->warm_last, k, total);
}

static void slot_release(nprfx_graph *g, pin_slot *s)
{
    if (s->e) s->e->pins--;
    internal_graph_frame_release(g, &s->scratch);
    s->e = NULL;
}

static void render_frame_release(render_frame *rf)
{
    for (int i = 0; i < rf->nbase; i++)
        slot_release(rf->g, &rf->base[i]);
    for (int i = 0; i < RING; i++)
        slot_release(rf->g, &rf->ring[i]);
    rf->nbase = 0;
    internal_graph_cache_evict(rf->g);
}

/* Input k of `reader` at frame, evaluated and pinned in a slot of rf (base: the render's own
 * inputs, else the ring of fetched frames), as the reader selects it. */
static nprfx_result pin_input(render_frame *rf, const gnode *reader, int k, int frame, int base,
                              nprfx_image *out)
{
    nprfx_graph *g = rf->g;
    pin_slot *slot = base ? &rf->base[rf->nbase++] : &rf->ring[rf->nfetch++ % RING];
    slot_release(g, slot);
    centry *e;
    nprfx_result r = internal_graph_eval(g, reader->inputs[k].src, frame, &e);
    if (r) return r;
    e->pins++;
    slot->e = e;
    return internal_graph_select_input(g, reader, k, e, out, &slot->scratch);
}

static nprfx_result fetch_input(render_frame *rf, int k, int frame, int base, nprfx_image *out)
{
    nprfx_graph *g = rf->g;
    const gnode *n = &g->nodes[rf->node];
    if (k < 0 || k >= n->ninputs || n->inputs[k].src < 0)
        return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                           "node '%s': input '%s' is not connected", n->name,
                           k >= 0 && k < n->ninputs ? n->desc->inputs[k].name : "?");
    return pin_input(rf, n, k, frame, base, out);
}

static nprfx_result fetch_cb(void *user, int input, double time, nprfx_image *out)
{
    int frame = (int)(time < 0 ? time - 0.5 : time + 0.5);
    warmup_progress(user, frame);
    return fetch_input(user, input, frame, 0, out);
}

const nprfx_node_desc *nprfx_graph_hook_upstream(void *fetch_user, int input,
                                                 const nprfx_value **params)
{
    render_frame *rf = fetch_user;
    const gnode *n = &rf->g->nodes[rf->node];
    if (input < 0 || input >= n->ninputs || n->inputs[input].src < 0) return NULL;
    const gnode *up = &rf->g->nodes[n->inputs[input].src];
    if (up->kind != GK_NODE) return NULL;
    if (params) *params = up->params;
    return up->desc;
}

nprfx_result nprfx_graph_hook_fetch_upstream(void *fetch_user, int input, int up_input, int frame,
                                             nprfx_image *out)
{
    render_frame *rf = fetch_user;
    nprfx_graph *g = rf->g;
    const gnode *n = &g->nodes[rf->node];
    if (!nprfx_graph_hook_upstream(fetch_user, input, NULL))
        return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                           "node '%s': input %d is not connected to a processing node", n->name,
                           input);
    const gnode *up = &g->nodes[n->inputs[input].src];
    if (up_input < 0 || up_input >= up->ninputs || up->inputs[up_input].src < 0)
        return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT, "node '%s': input %d is not connected",
                           up->name, up_input);
    return pin_input(rf, up, up_input, frame, 0, out);
}

/* The span of frames node n reads to render `frame` (all inputs): rf's warm-up range. */
static void warmup_range(nprfx_graph *g, const gnode *n, const nprfx_value *params, int frame,
                         const int *in_ch, render_frame *rf)
{
    const nprfx_node_desc *d = n->desc;
    rf->frame = rf->warm_first = rf->warm_last = frame;
    if (!g->progress || !(d->flags & NPRFX_NODE_TEMPORAL)) return;
    nprfx_frames_query q = {frame, g->first_frame, g->last_frame, in_ch};
    for (int k = 0; k < d->num_inputs; k++) {
        nprfx_frame_range r[NPRFX_MAX_FRAME_RANGES];
        int nr = 0;
        if (nprfx_node_frames_needed(NULL, d, params, &q, k, r, &nr)) continue;
        for (int i = 0; i < nr; i++) {
            if (r[i].first < rf->warm_first) rf->warm_first = r[i].first;
            if (r[i].last > rf->warm_last) rf->warm_last = r[i].last;
        }
    }
}

/* Write the node's per-frame export (NPRFX_PARAM_EXPORT param set, desc->export_text given),
 * relative to the output directory like write nodes, through a temporary name. */
static nprfx_result export_node(nprfx_graph *g, const gnode *n, nprfx_render_args *a, int frame)
{
    const nprfx_node_desc *d = n->desc;
    if (!d->export_text) return NPRFX_OK;
    for (int i = 0; i < d->num_params; i++) {
        if (!(d->params[i].flags & NPRFX_PARAM_EXPORT) || !n->params[i].s || !n->params[i].s[0])
            continue;
        char path[4096];
        internal_graph_resolve_path(g, g->out_dir, n->params[i].s, frame, path, sizeof path);
        char *text = NULL;
        size_t len = 0;
        a->window = a->frame;
        char what[4200];
        snprintf(what, sizeof what, "export to %s", path);
        nprfx_context *ectx = NULL;
        nprfx_result r = nprfx_context_create_scoped(n->ctx, what, &ectx);
        if (!r) {
            a->ctx = ectx;
            r = nprfx_node_export(a, path, &text, &len);
            a->ctx = n->ctx;
        }
        if (!r) r = g->io.write_text(ectx, path, text, len);
        nprfx_context_destroy(ectx);
        free(text);
        if (r) return r;
    }
    return NPRFX_OK;
}

void internal_graph_render_args(nprfx_graph *g, gnode *n, int frame, nprfx_rect frame_rect,
                                nprfx_rect display, nprfx_value *varied, nprfx_render_args *a)
{
    const nprfx_node_desc *d = n->desc;
    memset(a, 0, sizeof *a);
    a->size = sizeof *a;
    a->ctx = n->ctx;
    a->node = d;
    a->time = frame;
    a->render_scale = internal_graph_param_scale(g, display);
    g->last_display = display;
    g->have_display = 1;
    a->vector_scale = 1.0; /* a plate's vectors are in its own pixels */
    a->frame = frame_rect;
    a->first_frame = g->first_frame;
    a->last_frame = g->last_frame;
    a->params = n->params;
    if (d->num_params <= 64) {
        a->params = internal_graph_variant_params(g, n, frame, varied);
        a->params = internal_graph_scale_params(n, a->params, a->render_scale, varied);
    }
    a->state = &n->state;
    a->items = &g->render_items;
}

static nprfx_result eval_node(nprfx_graph *g, int node, int frame, nprfx_image *im, char ***names,
                              gmeta *meta)
{
    gnode *n = &g->nodes[node];
    const nprfx_node_desc *d = n->desc;
    render_frame rf;
    memset(&rf, 0, sizeof rf);
    rf.g = g;
    rf.node = node;
    nprfx_image inputs[32];
    int in_ch[32];
    memset(inputs, 0, sizeof inputs);
    memset(in_ch, 0, sizeof in_ch);
    nprfx_result r = NPRFX_OK;
    if (d->num_inputs > 32) return nprfx_error(g->ctx, NPRFX_ERR_INTERNAL, "too many inputs");
    nprfx_rect frame_rect = {0, 0, 0, 0};
    int have_rect = 0, first_input = -1;
    for (int k = 0; k < d->num_inputs; k++) {
        if (n->inputs[k].src < 0) continue;
        if ((r = fetch_input(&rf, k, frame, 1, &inputs[k]))) goto done;
        in_ch[k] = inputs[k].channels;
        if (d->inputs[k].flags & NPRFX_INPUT_UNALIGNED) continue; /* e.g. a lookup map */
        if (!have_rect) {
            frame_rect = inputs[k].bounds;
            have_rect = 1;
            first_input = k;
            /* The output lies on its first aligned input's frame: same data window, display
             * window and pixel aspect, which a write puts back. */
            meta->display = rf.base[rf.nbase - 1].e->meta.display;
            meta->pixel_aspect = rf.base[rf.nbase - 1].e->meta.pixel_aspect;
        } else if (nprfx_rect_width(frame_rect) == nprfx_rect_width(inputs[k].bounds) &&
                   nprfx_rect_height(frame_rect) == nprfx_rect_height(inputs[k].bounds) &&
                   !nprfx_rect_equal(frame_rect, inputs[k].bounds)) {
            r = nprfx_error(g->ctx, NPRFX_ERR_SIZE_MISMATCH,
                            "node '%s': input '%s' has data window %dx%d%+d%+d but input '%s' has "
                            "%dx%d%+d%+d at frame %d",
                            n->name, d->inputs[k].name, nprfx_rect_width(inputs[k].bounds),
                            nprfx_rect_height(inputs[k].bounds), inputs[k].bounds.x0,
                            inputs[k].bounds.y0, d->inputs[first_input].name,
                            nprfx_rect_width(frame_rect), nprfx_rect_height(frame_rect),
                            frame_rect.x0, frame_rect.y0, frame);
            goto done;
        } else if (!nprfx_rect_equal(frame_rect, inputs[k].bounds)) {
            /* Name what differs: equal sizes at other origins would otherwise read "is 200x150
             * but ... is 200x150". Data windows are written as oiiotool does, WxH+X+Y. */
            const nprfx_rect a = inputs[k].bounds, b = frame_rect;
            int same_size = nprfx_rect_width(a) == nprfx_rect_width(b) &&
                            nprfx_rect_height(a) == nprfx_rect_height(b);
            if (same_size)
                r = nprfx_error(g->ctx, NPRFX_ERR_SIZE_MISMATCH,
                                "node '%s': input '%s' has data window %dx%d%+d%+d but input '%s' "
                                "has %dx%d%+d%+d at frame %d (same size, other origin)",
                                n->name, d->inputs[k].name, nprfx_rect_width(a),
                                nprfx_rect_height(a), a.x0, a.y0, d->inputs[first_input].name,
                                nprfx_rect_width(b), nprfx_rect_height(b), b.x0, b.y0, frame);
            else
                r = nprfx_error(
                    g->ctx, NPRFX_ERR_SIZE_MISMATCH,
                    "node '%s': input '%s' is %dx%d but input '%s' is %dx%d at frame %d", n->name,
                    d->inputs[k].name, nprfx_rect_width(a), nprfx_rect_height(a),
                    d->inputs[first_input].name, nprfx_rect_width(b), nprfx_rect_height(b), frame);
            goto done;
        }
    }
    if (!have_rect) {
        int w = 0, h = 0;
        if (!g->fmt_text || sscanf(g->fmt_text, "%dx%d", &w, &h) != 2) {
            r = nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                            "node '%s' has no input connected: give the graph a \"format\": "
                            "\"WxH\"",
                            n->name);
            goto done;
        }
        frame_rect = nprfx_rect_make(0, 0, w, h);
        meta->display = frame_rect;
        meta->pixel_aspect = 1.0f;
    }
    nprfx_output_info oi;
    if ((r = nprfx_node_output_info(n->ctx, d, n->params, in_ch, &oi))) goto done;
    char what[300]; /* a frame beyond the memory limit is refused, not attempted */
    snprintf(what, sizeof what, "node '%s': output frame", n->name);
    /* the windows below cover the frame: a node that sets all of its window gets it unset (a
     * host's render through the hook makes no such promise) */
    r = (d->flags & NPRFX_NODE_WRITES_WINDOW) && !g->has_hook
            ? internal_graph_frame_alloc_unset(g, node, what, frame_rect, oi.channels, im)
            : internal_graph_frame_alloc(g, node, what, frame_rect, oi.channels, im);
    if (r) goto done;
    nprfx_render_args a;
    nprfx_value varied[64];
    internal_graph_render_args(g, n, frame, frame_rect, meta->display, varied, &a);
    a.inputs = inputs;
    a.output = im;
    a.fetch = fetch_cb;
    a.fetch_user = &rf;
    int tile = g->tile > 0 ? g->tile : 1 << 30;
    double t0 = engine_now(), c0 = engine_cpu_now();
    warmup_range(g, n, a.params, frame, in_ch, &rf);
    rf.t0 = t0;
    for (int ty = frame_rect.y0; ty < frame_rect.y1 && !r; ty += tile)
        for (int tx = frame_rect.x0; tx < frame_rect.x1 && !r; tx += tile) {
            a.window = nprfx_rect_intersect(
                frame_rect, nprfx_rect_make(tx, ty, tx + (tile < (1 << 29) ? tile : frame_rect.x1),
                                            ty + (tile < (1 << 29) ? tile : frame_rect.y1)));
            r = g->has_hook ? g->hook.render(g->hook.user, &a, &n->instance)
                            : nprfx_node_render(&a);
        }
    g->render_seconds += engine_now() - t0;
    g->render_cpu_seconds += engine_cpu_now() - c0;
    /* what the render must at least move through memory: its inputs read once, its output
     * written once (bench's floor) */
    for (int k = 0; k < d->num_inputs; k++)
        if (in_ch[k])
            g->render_bytes += 4.0 * in_ch[k] * (double)nprfx_rect_width(inputs[k].bounds) *
                               nprfx_rect_height(inputs[k].bounds);
    g->render_bytes +=
        4.0 * oi.channels * (double)nprfx_rect_width(frame_rect) * nprfx_rect_height(frame_rect);
    if (!r) {
        internal_graph_count_state(g, n, nprfx_rect_width(frame_rect),
                                   nprfx_rect_height(frame_rect), in_ch, a.params);
        internal_graph_analysis_check(g, n, frame);
    }
    if (!r && !(g->has_hook && g->hook.exports)) r = export_node(g, n, &a, frame);
    if (r) { /* the message went out through n->ctx, naming the node */
        internal_graph_frame_release(g, im);
        goto done;
    }
    *names = internal_graph_names_dup(oi.names, oi.channels);
done:
    render_frame_release(&rf);
    return r;
}

/* Render one node whose inputs at frame are cached (and pinned), and cache its result. */
static nprfx_result eval_one(nprfx_graph *g, int node, int frame, centry **out)
{
    nprfx_image im;
    memset(&im, 0, sizeof im);
    char **names = NULL;
    gmeta meta;
    memset(&meta, 0, sizeof meta);
    nprfx_result r;
    int pooled = g->nodes[node].kind == GK_SYNTH;
    /* The node's own time for --stats: evaluations nested in it (a temporal node's fetches of
     * other frames) are counted in their own nodes. */
    double saved_child = g->child_seconds, t0 = engine_now();
    g->child_seconds = 0;
    switch (g->nodes[node].kind) {
    case GK_READ:
        r = internal_graph_read_plate(g, node, frame, &im, &names, &meta, &pooled);
        break;
    case GK_SYNTH:
        r = internal_graph_synth_plate(g, node, frame, &im, &names, &meta);
        break;
    case GK_NODE:
        r = eval_node(g, node, frame, &im, &names, &meta);
        break;
    default:
        r = nprfx_error(g->ctx, NPRFX_ERR_INTERNAL, "write nodes have no output");
        break;
    }
    /* A plate keeps only what its readers take: a 26-channel plate of which a graph reads 11
     * then holds 11 while a temporal reader's window keeps it (its channel types with it). */
    int from_reader = 0;
    if (!r && (g->nodes[node].kind == GK_READ || g->nodes[node].kind == GK_SYNTH))
        from_reader = !internal_graph_trim_plate(g, node, &im, &names, &meta, pooled) && !pooled;
    double el = engine_now() - t0;
    g->stats[node].seconds += el - g->child_seconds;
    g->stats[node].calls++;
    g->child_seconds = saved_child + el;
    if (r) {
        free(meta.types);
        return r;
    }
    *out = internal_graph_cache_insert(g, node, frame, &im, names, &meta);
    if (*out) (*out)->from_reader = from_reader;
    if (!*out) {
        free(meta.types);
        for (int c = 0; names && c < im.channels; c++) /* the entry did not take them */
            free(names[c]);
        free(names);
        if (from_reader) { /* the reader's own buffer, never the pool's */
            size_t bytes = (size_t)nprfx_rect_width(im.bounds) *
                           (size_t)nprfx_rect_height(im.bounds) * (size_t)im.channels *
                           sizeof(float);
            g->held_bytes -= bytes < g->held_bytes ? bytes : g->held_bytes;
            nprfx_image_free(&im);
        } else {
            internal_graph_frame_release(g, &im);
        }
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    return NPRFX_OK;
}

/* The evaluation's work: a node to evaluate at a frame; once its inputs are pushed (expanded),
 * the results they leave pinned on the pin stack from pin_base on. */
typedef struct work {
    int node, frame, expanded;
    size_t pin_base;
} work;

typedef struct eval_stacks {
    work *w;
    size_t nw, capw;
    centry **pin;
    size_t npin, cappin;
} eval_stacks;

static int push_work(eval_stacks *s, int node, int frame)
{
    if (s->nw == s->capw) {
        size_t n = s->capw ? s->capw * 2 : 64;
        work *w = realloc(s->w, n * sizeof *w);
        if (!w) return 0;
        s->w = w;
        s->capw = n;
    }
    s->w[s->nw++] = (work){node, frame, 0, 0};
    return 1;
}

static int push_pin(eval_stacks *s, centry *e)
{
    if (s->npin == s->cappin) {
        size_t n = s->cappin ? s->cappin * 2 : 64;
        centry **p = realloc(s->pin, n * sizeof *p);
        if (!p) return 0;
        s->pin = p;
        s->cappin = n;
    }
    e->pins++;
    s->pin[s->npin++] = e;
    return 1;
}

static void unpin_to(eval_stacks *s, size_t base)
{
    while (s->npin > base)
        s->pin[--s->npin]->pins--;
}

/* The memory plan: the node whose inputs these n entries are (one per connected input, possibly
 * repeated) has rendered; each has one consumer less. An entry is looked at once, as the first
 * one dropped may be further in the list. */
static void consume_inputs(nprfx_graph *g, centry **in, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        centry *e = in[i];
        if (!e) continue;
        int times = 1;
        for (size_t j = i + 1; j < n; j++)
            if (in[j] == e) {
                in[j] = NULL;
                times++;
            }
        e->uses -= times - 1;
        internal_graph_consumed(g, e);
    }
}

static nprfx_result out_of_memory(nprfx_graph *g, int node)
{
    return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory evaluating node '%s'",
                       g->nodes[node].name);
}

/* Evaluation is driven by an explicit work stack, not recursion, so a graph's depth never meets
 * the C stack: a node's inputs at the frame are evaluated first (input 0 first) and stay pinned
 * until the node has rendered, then the node's own result is pinned for the node that asked.
 * Results come from the cache when it still has them; the graph is acyclic (checked at load), so
 * the stack empties. Only temporal fetches of other frames re-enter here from inside a render. */
nprfx_result internal_graph_eval(nprfx_graph *g, int node, int frame, centry **out)
{
    centry *e = internal_graph_cache_find(g, node, frame);
    if (e) {
        *out = e;
        return NPRFX_OK;
    }
    if (g->fetch_depth >= NPRFX_GRAPH_MAX_FETCH_DEPTH)
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "node '%s': temporal nodes nest more than %d deep (each fetches "
                           "other frames of the next)",
                           g->nodes[node].name, NPRFX_GRAPH_MAX_FETCH_DEPTH);
    g->fetch_depth++;
    eval_stacks s;
    memset(&s, 0, sizeof s);
    nprfx_result r = push_work(&s, node, frame) ? NPRFX_OK : out_of_memory(g, node);
    while (!r && s.nw > 0) {
        work *w = &s.w[s.nw - 1];
        if (!w->expanded) {
            if ((e = internal_graph_cache_find(g, w->node, w->frame))) {
                s.nw--;
                if (!push_pin(&s, e)) r = out_of_memory(g, node);
                continue;
            }
            w->expanded = 1;
            w->pin_base = s.npin;
            const gnode *n = &g->nodes[w->node];
            int f = w->frame; /* w moves when the stack grows */
            for (int k = n->ninputs - 1; k >= 0 && !r; k--)
                if (n->inputs[k].src >= 0 && !push_work(&s, n->inputs[k].src, f))
                    r = out_of_memory(g, node);
            continue;
        }
        r = eval_one(g, w->node, w->frame, &e);
        size_t top = s.npin;
        unpin_to(&s, w->pin_base);
        if (!r) consume_inputs(g, s.pin + w->pin_base, top - w->pin_base);
        s.nw--;
        if (!r && !push_pin(&s, e)) r = out_of_memory(g, node);
    }
    if (!r) *out = s.pin[0]; /* the root's result, the only pin left */
    unpin_to(&s, 0);
    free(s.w);
    free(s.pin);
    g->fetch_depth--;
    return r;
}

/* Thresholds of nprfx_graph_cost_warnings. A frame of an HD plate through a few nodes takes a
 * second or so; 100,000 of them are a day. A footprint of 10,000 pixels (morphology radius 56)
 * makes an HD frame 2e10 reads a pass, tens of seconds on a workstation. */
#define COST_MANY_FRAMES 100000
#define COST_MANY_TAPS 10000.0

int nprfx_graph_cost_warnings(nprfx_graph *g, int frames, char *buf, size_t n)
{
    int count = 0;
    size_t used = 0;
    if (n) buf[0] = 0;
#define COST_SAY(...)                                                                              \
    do {                                                                                           \
        if (used < n) used += (size_t)snprintf(buf + used, n - used, __VA_ARGS__);                 \
        count++;                                                                                   \
    } while (0)
    if (frames > COST_MANY_FRAMES)
        COST_SAY("%d frames: at one second a frame that is %.0f hours\n", frames, frames / 3600.0);
    for (int i = 0; i < g->count; i++) {
        const gnode *nd = &g->nodes[i];
        int fp = 0;
        if (nd->kind != GK_NODE || nprfx_node_footprint(NULL, nd->desc, nd->params, &fp) || fp <= 0)
            continue;
        double taps = (2.0 * fp + 1.0) * (2.0 * fp + 1.0);
        if (taps > COST_MANY_TAPS)
            COST_SAY("node '%s' (%s) reads up to %.0f pixels (radius %d) for every pixel: %.1e "
                     "reads per 1920x1080 frame\n",
                     nd->name, nd->desc->id, taps, fp, taps * 1920.0 * 1080.0);
    }
#undef COST_SAY
    return count;
}
