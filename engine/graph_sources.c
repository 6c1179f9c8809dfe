/* nprfx graph engine — what a graph reads from its plates, for a front end that feeds it from
 * somewhere other than files (the OpenFX look plug-ins serve a host's clips as the plates): each
 * read node, whether it is a frame sequence or one file, and the canonical AOVs the graph's
 * inputs take from it; and one AOV of a plate as those inputs receive it (the test host serves
 * clips from it). */
#include <stdlib.h>
#include <string.h>

#include "graph_model.h"
#include "graph_names.h"
#include "graph_resolve.h"
#include "graph_scale.h"
#include "nprfx/aov.h"
#include "nprfx/graph.h"
#include "nprfx/seq.h"

/* The AOV bits of one selection or hint (sep between items), and whether an item names plate
 * channels rather than an AOV. */
static unsigned aovs_of(const char *list, char sep, int *raw)
{
    unsigned bits = 0;
    int any_raw = 0;
    for (const char *p = list; p && *p;) {
        const char *e = strchr(p, sep);
        size_t len = e ? (size_t)(e - p) : strlen(p);
        char item[128], comp[16];
        if (len < sizeof item) {
            memcpy(item, p, len);
            item[len] = 0;
            int aov = internal_graph_canonical_parse(item, comp, sizeof comp);
            if (aov >= 0)
                bits |= 1u << aov;
            else
                any_raw = 1;
        }
        /* a hint's alternatives: the first canonical one is what the input asks for */
        if (sep == '|' && bits) break;
        p = e ? e + 1 : NULL;
    }
    if (raw) *raw = any_raw && !bits;
    return bits;
}

static int is_source(const gnode *n)
{
    return n->kind == GK_READ;
}

int nprfx_graph_source_count(const nprfx_graph *g)
{
    int count = 0;
    for (int i = 0; g && i < g->count; i++)
        count += is_source(&g->nodes[i]);
    return count;
}

nprfx_result nprfx_graph_source(const nprfx_graph *g, int i, nprfx_graph_source_info *out)
{
    int node = -1;
    for (int k = 0, seen = 0; k < g->count; k++)
        if (is_source(&g->nodes[k]) && seen++ == i) {
            node = k;
            break;
        }
    if (node < 0)
        return nprfx_error(g->ctx, NPRFX_ERR_INVALID_ARGUMENT, "the graph has no read node %d", i);
    const gnode *src = &g->nodes[node];
    nprfx_graph_source_info s;
    memset(&s, 0, sizeof s);
    s.size = sizeof s;
    s.node = node;
    s.name = src->name;
    s.sequence = src->path && nprfx_seq_has_pattern(src->path);
    for (int n = 0; n < g->count; n++) {
        const gnode *reader = &g->nodes[n];
        for (int k = 0; k < reader->ninputs; k++) {
            const gref *ref = &reader->inputs[k];
            if (ref->src != node) continue;
            int raw = 0;
            unsigned bits = 0;
            if (ref->sel)
                bits = aovs_of(ref->sel, ',', &raw);
            else if (reader->kind == GK_NODE && reader->desc->inputs[k].aov)
                bits = aovs_of(reader->desc->inputs[k].aov, '|', &raw);
            else
                bits = 1u << NPRFX_AOV_BEAUTY; /* the whole plate: its picture */
            if (raw && !s.raw) s.raw = ref->sel ? ref->sel : reader->desc->inputs[k].aov;
            s.aovs |= bits;
        }
    }
    if (s.sequence) {
        /* What stands in for an AOV a plate lacks (graph_aovs.c) is read too: the picture (for
         * albedo, light, and optical flow for motion); uv and position for rest, position for
         * uv, and depth (a camera position) for all three. Coverage is the picture's alpha. */
        s.aovs |= 1u << NPRFX_AOV_BEAUTY;
        if (s.aovs & (1u << NPRFX_AOV_REST)) s.aovs |= 1u << NPRFX_AOV_UV;
        if (s.aovs & ((1u << NPRFX_AOV_REST) | (1u << NPRFX_AOV_UV)))
            s.aovs |= 1u << NPRFX_AOV_POSITION;
        if (s.aovs & ((1u << NPRFX_AOV_REST) | (1u << NPRFX_AOV_UV) | (1u << NPRFX_AOV_POSITION)))
            s.aovs |= 1u << NPRFX_AOV_DEPTH;
    }
    size_t n = out->size && out->size < sizeof s ? out->size : sizeof s;
    memcpy(out, &s, n);
    out->size = n;
    return NPRFX_OK;
}

nprfx_result nprfx_graph_aov_channels(nprfx_graph *g, int node, int aov, const char *const *names,
                                      int nc, int *idx, int *count)
{
    if (node < 0 || node >= g->count || g->nodes[node].kind != GK_READ || !nprfx_aov_name(aov))
        return nprfx_error(g->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "nprfx_graph_aov_channels: node %d is no read node, or AOV %d is none",
                           node, aov);
    /* A reader of the AOV by name: a write node's input, which takes what the selection says. */
    gref ref;
    memset(&ref, 0, sizeof ref);
    ref.src = node;
    ref.sel = (char *)nprfx_aov_name(aov);
    ref.text = g->nodes[node].name;
    gnode reader;
    memset(&reader, 0, sizeof reader);
    reader.name = (char *)nprfx_aov_name(aov);
    reader.kind = GK_WRITE;
    reader.ninputs = 1;
    reader.inputs = &ref;
    return internal_graph_input_channels(g, &reader, 0, names, nc, idx, count);
}

nprfx_result nprfx_graph_eval_aov(nprfx_graph *g, int node, int aov, int frame, nprfx_image *out)
{
    memset(out, 0, sizeof *out);
    if (node < 0 || node >= g->count || g->nodes[node].kind != GK_READ || !nprfx_aov_name(aov))
        return nprfx_error(g->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "nprfx_graph_eval_aov: node %d is no read node, or AOV %d is none", node,
                           aov);
    nprfx_image im;
    const char *const *names = NULL;
    nprfx_result r = nprfx_graph_eval(g, g->nodes[node].name, frame, &im, &names);
    if (r) return r;
    int idx[256], count = 0;
    if ((r = nprfx_graph_aov_channels(g, node, aov, names, im.channels, idx, &count))) return r;
    if ((r = nprfx_image_alloc(g->ctx, im.bounds, count, out))) return r;
    for (int y = im.bounds.y0; y < im.bounds.y1; y++)
        for (int x = im.bounds.x0; x < im.bounds.x1; x++) {
            const float *s = nprfx_image_at(&im, x, y);
            float *d = nprfx_image_at(out, x, y);
            for (int c = 0; c < count; c++)
                d[c] = s[idx[c]];
        }
    return NPRFX_OK;
}

/* ---- the frames of a plate that evaluating a node reads -------------------------------------- */

typedef struct needs_walk {
    const nprfx_graph *g;
    int source, aov;
    unsigned present;    /* the AOVs the source has: the others are read through their fallbacks */
    int first, span;     /* the shot */
    unsigned char *seen; /* per node, per shot frame: visited */
    unsigned char *out;  /* per shot frame: read */
    int outside;         /* a frame outside the shot was read (then the node's frame, below) */
} needs_walk;

static void mark(needs_walk *w, int frame)
{
    if (frame >= w->first && frame < w->first + w->span)
        w->out[frame - w->first] = 1;
    else
        w->outside = 1;
}

/* What input reference ref, read at `frame`, takes from the walk's source AOV. */
static void mark_ref(needs_walk *w, const gnode *reader, int k, int frame)
{
    const gref *ref = &reader->inputs[k];
    unsigned bits;
    if (ref->sel)
        bits = aovs_of(ref->sel, ',', NULL);
    else if (reader->kind == GK_NODE && reader->desc->inputs[k].aov)
        bits = aovs_of(reader->desc->inputs[k].aov, '|', NULL);
    else
        bits = 1u << NPRFX_AOV_BEAUTY;
    if (w->aov < 0 || (bits & (1u << w->aov))) mark(w, frame);
    unsigned missing = bits & ~w->present;
    const unsigned motion = (1u << NPRFX_AOV_MOTION_PREV) | (1u << NPRFX_AOV_MOTION_NEXT);
    const unsigned beauty_for = motion | (1u << NPRFX_AOV_ALBEDO) |
                                (1u << NPRFX_AOV_DIFFUSE_LIGHT) | (1u << NPRFX_AOV_COVERAGE);
    const unsigned depth_for =
        (1u << NPRFX_AOV_REST) | (1u << NPRFX_AOV_UV) | (1u << NPRFX_AOV_POSITION);
    if ((w->aov < 0 || w->aov == NPRFX_AOV_BEAUTY) && (missing & beauty_for)) {
        mark(w, frame);
        /* optical flow on the picture: the frame and its neighbour on that side */
        if (missing & (1u << NPRFX_AOV_MOTION_PREV)) mark(w, frame - 1);
        if (missing & (1u << NPRFX_AOV_MOTION_NEXT)) mark(w, frame + 1);
    }
    if (w->aov == NPRFX_AOV_DEPTH && (missing & depth_for)) mark(w, frame);
}

static void walk(needs_walk *w, int node, int frame)
{
    const nprfx_graph *g = w->g;
    const gnode *n = &g->nodes[node];
    if (frame >= w->first && frame < w->first + w->span) {
        unsigned char *seen = &w->seen[(size_t)node * (size_t)w->span + (size_t)(frame - w->first)];
        if (*seen) return;
        *seen = 1;
    }
    if (n->kind != GK_NODE && n->kind != GK_WRITE) return;
    int in_ch[32];
    const nprfx_node_desc *d = n->kind == GK_NODE ? n->desc : NULL;
    int ninputs = n->ninputs < 32 ? n->ninputs : 32;
    for (int k = 0; k < ninputs; k++)
        in_ch[k] = n->inputs[k].src < 0             ? 0
                   : d && d->inputs[k].channels > 0 ? d->inputs[k].channels
                                                    : 1;
    nprfx_frames_query q = {frame, g->first_frame, g->last_frame, in_ch, n->state};
    /* the params as the render has them (scaled to the plate): a state is keyed by them */
    nprfx_value scaled[64];
    const nprfx_value *params = n->params;
    if (d && d->num_params <= 64 && g->have_display)
        params = internal_graph_scale_params(
            n, n->params, internal_graph_param_scale(g, g->last_display), scaled);
    for (int k = 0; k < ninputs; k++) {
        int src = n->inputs[k].src;
        if (src < 0) continue;
        nprfx_frame_range r[NPRFX_MAX_FRAME_RANGES];
        int nr = 1;
        r[0].first = r[0].last = frame;
        if (d && (d->flags & NPRFX_NODE_TEMPORAL) &&
            nprfx_node_frames_needed(NULL, d, params, &q, k, r, &nr) != NPRFX_OK) {
            nr = 1;
            r[0].first = g->last_frame >= g->first_frame ? g->first_frame : frame;
            r[0].last = g->last_frame >= g->first_frame ? g->last_frame : frame;
        }
        for (int i = 0; i < nr; i++)
            for (int f = r[i].first; f <= r[i].last; f++) {
                if (src == w->source)
                    mark_ref(w, n, k, f);
                else
                    walk(w, src, f);
            }
    }
}

nprfx_result nprfx_graph_frames_read(nprfx_graph *g, int node, int frame, int source, int aov,
                                     unsigned present, nprfx_frame_range *ranges, int max,
                                     int *count)
{
    *count = 0;
    if (node < 0 || node >= g->count || source < 0 || source >= g->count ||
        (aov >= 0 && !nprfx_aov_name(aov)))
        return nprfx_error(g->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "nprfx_graph_frames_read: no node %d, read %d or AOV %d", node, source,
                           aov);
    needs_walk w;
    memset(&w, 0, sizeof w);
    w.g = g;
    w.source = source;
    w.aov = aov;
    w.present = present;
    int have_shot = g->last_frame >= g->first_frame;
    w.first = have_shot ? g->first_frame : frame;
    w.span = have_shot ? g->last_frame - g->first_frame + 1 : 1;
    w.seen = calloc((size_t)g->count * (size_t)w.span, 1);
    w.out = calloc((size_t)w.span, 1);
    if (!w.seen || !w.out) {
        free(w.seen);
        free(w.out);
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    walk(&w, node, frame);
    /* Runs of read frames, as many as fit; the last takes the rest (a superset). */
    int n = 0;
    for (int f = 0; f < w.span; f++) {
        if (!w.out[f]) continue;
        int e = f;
        while (e + 1 < w.span && w.out[e + 1])
            e++;
        if (n < max) {
            ranges[n].first = w.first + f;
            ranges[n].last = w.first + e;
            n++;
        } else if (max > 0) {
            ranges[max - 1].last = w.first + e;
        }
        f = e;
    }
    /* A frame outside the shot (a graph without one): the frame asked for, which the read
     * serves as it is. */
    if (w.outside && n < max && !have_shot) {
        ranges[n].first = ranges[n].last = frame;
        n++;
    }
    free(w.seen);
    free(w.out);
    *count = n;
    return NPRFX_OK;
}
