/* nprfx graph engine — strip renders (docs/design.md §1 "Memory").
 *
 * A write whose whole chain renders by rows (reads of EXR files, nodes with NPRFX_NODE_ROWS and
 * a footprint) goes a strip of rows at a time: every node of the chain renders the strip's rows
 * plus the margin its readers' footprints need, from inputs that hold just those rows; the plates
 * are read a block of chunks at a time (nprfx_io_rows_read) and the output is written strip by
 * strip under a temporary name, renamed once its last row is in (nprfx_io_rows_finish). So the
 * memory a frame takes is bounded by the strip's height, not the frame's. The pixels are the
 * whole frame's, bit for bit: a node's result is the same whatever the window (§1, render
 * contract), and NPRFX_NODE_ROWS promises it reads no input pixel beyond its footprint. Strips
 * do not go through the result cache: each strip's buffers go back to the pool as soon as their
 * last reader in the strip has rendered. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "graph_scale.h"

#include "nprfx/graph.h"
#include "graph_eval.h"
#include "graph_files.h"
#include "graph_frames.h"
#include "graph_memory.h"
#include "graph_extras.h"
#include "graph_model.h"
#include "graph_read.h"
#include "graph_resolve.h"
#include "graph_strips.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "nprfx/io.h"
#include "engine_util.h"

/* One node of the chain, as a strip render needs it. */
typedef struct snode {
    int node;
    int channels;    /* of its result */
    char **names;    /* of its result (owned) */
    int footprint;   /* rows its render reads beyond its window (nodes) */
    int in_channels; /* the channels its inputs select, together (nodes) */
    int margin;      /* rows above and below a strip its readers need of it */
    int uses, left;  /* readers in the chain (edges), and those still to render in this strip */
    nprfx_rect display;
    float pixel_aspect;
    unsigned char *types; /* a read's per-channel file types (owned), NULL for nodes */
    /* reads */
    char file[4096];
    nprfx_plate shape;
    nprfx_row_reader *rr;
    /* the strip's rows of its result */
    nprfx_image buf;
    int own; /* buf is a read's malloc'd plate, not a pool frame */
} snode;

typedef struct strips {
    nprfx_graph *g;
    const int *writes; /* the writes rendered together (their chains share nodes) */
    int nwrites;
    int n;
    snode *s;
    int *slot; /* per graph node: its index in s, or -1 */
    nprfx_rect frame;
    int have_frame;
} strips;

/* The nodes write nodes writes[0..nw) depend on, each once, inputs before their readers, found
 * without recursion (a graph's depth is limited only by its node count). */
static nprfx_result chain_order(nprfx_graph *g, const int *writes, int nw, int **order, int *count)
{
    *order = NULL;
    *count = 0;
    int *seen = calloc((size_t)g->count, sizeof *seen);
    int *stack = malloc((size_t)g->count * 2 * sizeof *stack);
    int *out = malloc((size_t)g->count * sizeof *out);
    if (!seen || !stack || !out) {
        free(seen);
        free(stack);
        free(out);
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    int top = 0, n = 0;
    for (int i = 0; i < nw; i++) {
        int src = g->nodes[writes[i]].inputs[0].src;
        if (src < 0 || seen[src]) continue;
        stack[0] = src;
        stack[1] = 0;
        seen[src] = 1;
        top = 1;
        while (top > 0) {
            int at = stack[2 * (top - 1)], *k = &stack[2 * (top - 1) + 1];
            const gnode *nd = &g->nodes[at];
            int next = -1;
            while (*k < nd->ninputs && next < 0) {
                int s = nd->inputs[(*k)++].src;
                if (s >= 0 && !seen[s]) next = s;
            }
            if (next >= 0) {
                seen[next] = 1;
                stack[2 * top] = next;
                stack[2 * top + 1] = 0;
                top++;
            } else {
                out[n++] = at;
                top--;
            }
        }
    }
    free(seen);
    free(stack);
    *order = out;
    *count = n;
    return NPRFX_OK;
}

#define WHY(...)                                                                                   \
    do {                                                                                           \
        if (why && n) snprintf(why, n, __VA_ARGS__);                                               \
    } while (0)

int internal_graph_strips_possible(nprfx_graph *g, int node, char *why, size_t n)
{
    const gnode *w = &g->nodes[node];
    if (why && n) why[0] = 0;
    if (w->kind != GK_WRITE || w->inputs[0].src < 0 || g->has_hook || g->variant) return 0;
    if (w->preview) {
        WHY("write node '%s' makes a preview, which needs its whole frame", w->name);
        return 0;
    }
    int *order, count, ok = 1;
    if (chain_order(g, &node, 1, &order, &count)) return 0;
    for (int i = 0; i < count && ok; i++) {
        const gnode *nd = &g->nodes[order[i]];
        if (nd->kind == GK_READ) continue;
        if (nd->kind != GK_NODE) {
            WHY("node '%s' (%s) makes whole frames", nd->name,
                nd->kind == GK_SYNTH ? "synth" : "write");
            ok = 0;
            break;
        }
        const nprfx_node_desc *d = nd->desc;
        int fp = -1, aligned = 0;
        if (!(d->flags & NPRFX_NODE_ROWS) || (d->flags & NPRFX_NODE_TEMPORAL) || d->export_text ||
            nprfx_node_footprint(NULL, d, nd->params, &fp) || fp < 0) {
            WHY("node '%s' (%s) needs its inputs' whole frames", nd->name, d->id);
            ok = 0;
            break;
        }
        for (int k = 0; k < nd->ninputs && ok; k++) {
            if (nd->inputs[k].src < 0) continue;
            if (d->inputs[k].flags & NPRFX_INPUT_UNALIGNED) {
                WHY("node '%s' (%s): input '%s' is read whole", nd->name, d->id, d->inputs[k].name);
                ok = 0;
            }
            aligned = 1;
        }
        if (ok && !aligned) {
            WHY("node '%s' (%s) has no input to take its rows from", nd->name, d->id);
            ok = 0;
        }
    }
    free(order);
    return ok;
}

static void strips_free(strips *st)
{
    for (int i = 0; st->s && i < st->n; i++) {
        snode *s = &st->s[i];
        for (int c = 0; s->names && c < s->channels; c++)
            free(s->names[c]);
        free(s->names);
        free(s->types);
        st->g->io.rows_close(s->rr);
        nprfx_plate_free(&s->shape);
        if (s->own) {
            free(s->buf.data);
        } else if (s->buf.data) {
            internal_graph_frame_release(st->g, &s->buf);
        }
    }
    free(st->s);
    free(st->slot);
    memset(st, 0, sizeof *st);
}

/* The chains of writes[0..nw) at frame, together: their nodes in order, each once, each
 * result's channels, the plates opened for rows, the margins. Files are opened (headers only),
 * no pixel is read. */
static nprfx_result strips_prepare(nprfx_graph *g, const int *writes, int nw, int frame, strips *st)
{
    memset(st, 0, sizeof *st);
    st->g = g;
    st->writes = writes;
    st->nwrites = nw;
    int *order = NULL;
    nprfx_result r = chain_order(g, writes, nw, &order, &st->n);
    if (r) return r;
    st->s = calloc((size_t)(st->n ? st->n : 1), sizeof *st->s);
    st->slot = malloc((size_t)g->count * sizeof *st->slot);
    if (!st->s || !st->slot) {
        free(order);
        strips_free(st);
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    for (int i = 0; i < g->count; i++)
        st->slot[i] = -1;
    for (int i = 0; i < st->n; i++) {
        st->s[i].node = order[i];
        st->slot[order[i]] = i;
    }
    free(order);
    for (int i = 0; i < st->n && !r; i++) {
        snode *s = &st->s[i];
        gnode *nd = &g->nodes[s->node];
        if (nd->kind == GK_READ) {
            r = internal_graph_read_rows_open(g, s->node, frame, s->file, sizeof s->file, &s->shape,
                                              &s->rr);
            if (r) break;
            s->channels = s->shape.nchannels + internal_graph_extra_count(nd);
            s->names = calloc((size_t)s->channels, sizeof *s->names);
            s->types = calloc((size_t)s->channels, 1);
            if (!s->names || !s->types) {
                r = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
                break;
            }
            for (int c = 0; c < s->channels; c++) {
                const char *name = c < s->shape.nchannels
                                       ? s->shape.names[c]
                                       : internal_graph_extra_name(nd, c - s->shape.nchannels);
                s->names[c] = engine_strdup(name);
                s->types[c] = c < s->shape.nchannels ? s->shape.types[c] : NPRFX_PIXEL_FLOAT;
                if (!s->names[c]) r = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
            }
            s->display = s->shape.display;
            s->pixel_aspect = s->shape.pixel_aspect;
            if (!st->have_frame) {
                st->frame = s->shape.bounds;
                st->have_frame = 1;
            } else if (!nprfx_rect_equal(st->frame, s->shape.bounds)) {
                const nprfx_rect a = s->shape.bounds, b = st->frame;
                r = nprfx_error(g->ctx, NPRFX_ERR_SIZE_MISMATCH,
                                "strips: read node '%s' has data window %dx%d%+d%+d, another read "
                                "of the chain %dx%d%+d%+d at frame %d",
                                nd->name, nprfx_rect_width(a), nprfx_rect_height(a), a.x0, a.y0,
                                nprfx_rect_width(b), nprfx_rect_height(b), b.x0, b.y0, frame);
            }
            continue;
        }
        const nprfx_node_desc *d = nd->desc;
        int in_ch[32] = {0}, first = -1;
        if (d->num_inputs > 32) {
            r = nprfx_error(g->ctx, NPRFX_ERR_INTERNAL, "too many inputs");
            break;
        }
        for (int k = 0; k < d->num_inputs && !r; k++) {
            int src = nd->inputs[k].src;
            if (src < 0) continue;
            const snode *in = &st->s[st->slot[src]];
            int idx[256];
            r = internal_graph_input_channels(g, nd, k, (const char *const *)in->names,
                                              in->channels, idx, &in_ch[k]);
            s->in_channels += in_ch[k];
            if (first < 0) first = st->slot[src];
        }
        if (r) break;
        nprfx_output_info oi;
        if ((r = nprfx_node_output_info(nd->ctx, d, nd->params, in_ch, &oi))) break;
        s->display = st->s[first].display;
        s->pixel_aspect = st->s[first].pixel_aspect;
        /* the footprint of the params it renders with, at the plate's scale */
        nprfx_value scaled[64];
        const nprfx_value *params =
            d->num_params <= 64
                ? internal_graph_scale_params(nd, nd->params,
                                              internal_graph_param_scale(g, s->display), scaled)
                : nd->params;
        if ((r = nprfx_node_footprint(nd->ctx, d, params, &s->footprint))) break;
        s->channels = oi.channels;
        s->names = internal_graph_names_dup(oi.names, oi.channels);
        if (!s->names) r = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    /* Margins, from the writes back: a node's rows are its readers' rows grown by their
     * footprints. Uses: the readers of each result within the chains, the writes included. */
    if (!r) {
        for (int i = 0; i < nw; i++)
            st->s[st->slot[g->nodes[writes[i]].inputs[0].src]].uses++;
        for (int i = st->n - 1; i >= 0; i--) {
            const snode *s = &st->s[i];
            const gnode *nd = &g->nodes[s->node];
            if (nd->kind != GK_NODE) continue;
            for (int k = 0; k < nd->ninputs; k++) {
                int src = nd->inputs[k].src;
                if (src < 0) continue;
                snode *in = &st->s[st->slot[src]];
                int m = s->margin + s->footprint;
                if (m > in->margin) in->margin = m;
                in->uses++;
            }
        }
    }
    if (r) strips_free(st);
    return r;
}

/* The rows of a strip a chain node makes: the strip's grown by its margin, inside the frame. */
static nprfx_rect node_rows(const strips *st, const snode *s, int y0, int y1)
{
    int r0 = y0 - s->margin, r1 = y1 + s->margin;
    if (r0 < st->frame.y0) r0 = st->frame.y0;
    if (r1 > st->frame.y1) r1 = st->frame.y1;
    return nprfx_rect_make(st->frame.x0, r0, st->frame.x1, r1);
}

static void release_buf(strips *st, snode *s)
{
    if (!s->buf.data) return;
    if (s->own) {
        size_t bytes = (size_t)nprfx_rect_width(s->buf.bounds) *
                       (size_t)nprfx_rect_height(s->buf.bounds) * (size_t)s->buf.channels *
                       sizeof(float);
        st->g->held_bytes -= bytes < st->g->held_bytes ? bytes : st->g->held_bytes;
        free(s->buf.data);
    } else {
        internal_graph_frame_release(st->g, &s->buf);
    }
    memset(&s->buf, 0, sizeof s->buf);
    s->own = 0;
}

/* The channels `reader`'s input k takes of chain node `in`'s strip: a view of them when they
 * are adjacent, else packed into *scratch (a pool frame; the caller releases it). */
static nprfx_result select_rows(strips *st, const gnode *reader, int k, snode *in,
                                nprfx_image *view, nprfx_image *scratch)
{
    nprfx_graph *g = st->g;
    int idx[256], count = 0;
    nprfx_result r = internal_graph_input_channels(g, reader, k, (const char *const *)in->names,
                                                   in->channels, idx, &count);
    if (r) return r;
    int contiguous = 1;
    for (int c = 1; c < count; c++)
        contiguous &= idx[c] == idx[0] + c;
    if (contiguous) {
        *view = nprfx_image_channels(&in->buf, idx[0], count);
        return NPRFX_OK;
    }
    char what[600];
    snprintf(what, sizeof what, "node '%s': input %d (channels from '%s'), a strip", reader->name,
             k, g->nodes[in->node].name);
    if ((r = internal_graph_frame_alloc(g, reader - g->nodes, what, in->buf.bounds, count,
                                        scratch)))
        return r;
    for (int y = in->buf.bounds.y0; y < in->buf.bounds.y1; y++)
        for (int x = in->buf.bounds.x0; x < in->buf.bounds.x1; x++) {
            const float *p = nprfx_image_at(&in->buf, x, y);
            float *q = nprfx_image_at(scratch, x, y);
            for (int c = 0; c < count; c++)
                q[c] = p[idx[c]];
        }
    *view = *scratch;
    return NPRFX_OK;
}

/* Chain node s's rows of the strip [y0, y1). */
static nprfx_result render_rows(strips *st, snode *s, int frame, int y0, int y1)
{
    nprfx_graph *g = st->g;
    gnode *nd = &g->nodes[s->node];
    nprfx_rect rows = node_rows(st, s, y0, y1);
    double t0 = engine_now();
    nprfx_result r = NPRFX_OK;
    if (nd->kind == GK_READ) {
        nprfx_plate p;
        r = internal_graph_read_rows(g, s->node, s->file, s->rr, &s->shape, rows.y0, rows.y1, &p);
        if (r) return r;
        s->buf.data = p.pixels;
        s->buf.channels = p.nchannels;
        s->buf.pixel_stride = p.nchannels;
        s->buf.row_stride = (ptrdiff_t)nprfx_rect_width(p.bounds) * p.nchannels;
        s->buf.bounds = p.bounds;
        s->own = 1;
        p.pixels = NULL;
        nprfx_plate_free(&p);
        internal_graph_frame_adopt(g, s->node, &s->buf);
    } else {
        const nprfx_node_desc *d = nd->desc;
        nprfx_image inputs[32], scratch[32];
        memset(inputs, 0, sizeof inputs);
        memset(scratch, 0, sizeof scratch);
        for (int k = 0; k < d->num_inputs && !r; k++)
            if (nd->inputs[k].src >= 0)
                r = select_rows(st, nd, k, &st->s[st->slot[nd->inputs[k].src]], &inputs[k],
                                &scratch[k]);
        char what[300];
        snprintf(what, sizeof what, "node '%s': output rows", nd->name);
        if (!r) r = internal_graph_frame_alloc(g, s->node, what, rows, s->channels, &s->buf);
        if (!r) {
            /* the same arguments as a whole frame's, its params varied at this frame */
            nprfx_render_args a;
            nprfx_value varied[64];
            internal_graph_render_args(g, nd, frame, st->frame, s->display, varied, &a);
            a.window = rows;
            a.inputs = inputs;
            a.output = &s->buf;
            double tr = engine_now();
            r = nprfx_node_render(&a);
            g->render_seconds += engine_now() - tr;
            if (!r) {
                int in_ch[32] = {0};
                for (int k = 0; k < d->num_inputs; k++)
                    in_ch[k] = inputs[k].data ? inputs[k].channels : 0;
                internal_graph_count_state(g, nd, nprfx_rect_width(st->frame),
                                           nprfx_rect_height(st->frame), in_ch, a.params);
            }
        }
        for (int k = 0; k < d->num_inputs; k++)
            internal_graph_frame_release(g, &scratch[k]);
        /* Each input's strip goes back as soon as its last reader in the chain has rendered. */
        for (int k = 0; k < d->num_inputs && !r; k++) {
            if (nd->inputs[k].src < 0) continue;
            snode *in = &st->s[st->slot[nd->inputs[k].src]];
            if (--in->left == 0) release_buf(st, in);
        }
    }
    g->stats[s->node].seconds += engine_now() - t0;
    return r;
}

int internal_graph_strip_group(nprfx_graph *g, int write, int *group)
{
    /* Flood over shared chain nodes: mark holds the group's chain nodes so far; a strip write
     * whose chain meets them joins, and its nodes are marked; until none joins. */
    unsigned char *mark = calloc((size_t)g->count, 1), *in = calloc((size_t)g->count, 1);
    int n = 0;
    if (!mark || !in) goto done;
    in[write] = 1;
    for (int grown = 1; grown;) {
        grown = 0;
        for (int w = 0; w < g->count; w++) {
            if (g->nodes[w].kind != GK_WRITE) continue;
            if (!in[w] && !internal_graph_strips_possible(g, w, NULL, 0)) continue;
            int *order, count;
            if (chain_order(g, &w, 1, &order, &count)) goto done;
            int meets = in[w];
            for (int k = 0; k < count && !meets; k++)
                meets = mark[order[k]];
            if (meets) {
                for (int k = 0; k < count; k++)
                    if (!mark[order[k]]) mark[order[k]] = grown = 1;
                if (!in[w]) in[w] = grown = 1;
            }
            free(order);
        }
    }
    for (int w = 0; w < g->count; w++)
        if (in[w]) group[n++] = w;
done:
    if (n == 0) group[n++] = write; /* out of memory: alone, as before */
    free(mark);
    free(in);
    return n;
}

/* One write of a strip render: its file, open for rows, and the channels it writes. */
typedef struct swrite {
    snode *src;
    nprfx_row_writer *out;
} swrite;

nprfx_result internal_graph_write_strips(nprfx_graph *g, const int *writes, int nw, int frame)
{
    strips st;
    nprfx_result r = strips_prepare(g, writes, nw, frame, &st);
    if (r) return r;
    double t0 = engine_now();
    swrite *sw = calloc((size_t)nw, sizeof *sw);
    if (!sw) r = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    for (int i = 0; !r && i < nw; i++) {
        gnode *w = &g->nodes[writes[i]];
        snode *src = sw[i].src = &st.s[st.slot[w->inputs[0].src]];
        char path[4096];
        internal_graph_resolve_path(g, g->out_dir, w->path, frame, path, sizeof path);
        r = internal_graph_check_not_input(g, w, path, frame);
        /* The channels written, their names and file types, as write_node takes them. */
        int idx[256], count = 0;
        if (!r)
            r = internal_graph_input_channels(g, w, 0, (const char *const *)src->names,
                                              src->channels, idx, &count);
        const char *names[256];
        unsigned char types[256];
        for (int c = 0; !r && c < count; c++) {
            names[c] = src->names[idx[c]];
            types[c] = src->types ? src->types[idx[c]] : NPRFX_PIXEL_FLOAT;
        }
        if (!r) {
            nprfx_write_options wo = {sizeof wo, w->compression ? w->compression : "zip", w->half};
            wo.types = src->types ? types : NULL;
            wo.pixel_aspect = src->pixel_aspect;
            const nprfx_rect *display = nprfx_rect_empty(src->display) ? NULL : &src->display;
            r = g->io.rows_create(w->ctx, path, st.frame, count, names, display, &wo, &sw[i].out);
        }
    }
    double tw = engine_now() - t0;
    const int step = g->strip_rows > 0 ? g->strip_rows : 64;
    for (int y0 = st.frame.y0; y0 < st.frame.y1 && !r; y0 += step) {
        int y1 = y0 + step < st.frame.y1 ? y0 + step : st.frame.y1;
        for (int i = 0; i < st.n; i++)
            st.s[i].left = st.s[i].uses;
        for (int i = 0; i < st.n && !r; i++)
            r = render_rows(&st, &st.s[i], frame, y0, y1);
        double t1 = engine_now();
        for (int i = 0; i < nw && !r; i++) {
            const gnode *w = &g->nodes[writes[i]];
            nprfx_image view, scratch;
            memset(&scratch, 0, sizeof scratch);
            r = select_rows(&st, w, 0, sw[i].src, &view, &scratch);
            /* the strip's own rows: a source that another chain node also reads holds its
             * margin too */
            if (!r)
                view = nprfx_image_crop(&view, nprfx_rect_make(st.frame.x0, y0, st.frame.x1, y1));
            if (!r) r = g->io.rows_write(w->ctx, sw[i].out, &view);
            internal_graph_frame_release(g, &scratch);
            if (--sw[i].src->left == 0) release_buf(&st, sw[i].src);
        }
        tw += engine_now() - t1;
    }
    /* Every file is finished (renamed into place, or its temporary removed) whatever failed. */
    double t1 = engine_now();
    for (int i = 0; sw && i < nw; i++) {
        if (!sw[i].out) continue;
        nprfx_result fr = g->io.rows_finish(g->nodes[writes[i]].ctx, sw[i].out, !r);
        if (!r) r = fr;
    }
    tw += engine_now() - t1;
    for (int i = 0; i < st.n; i++)
        g->stats[st.s[i].node].calls++;
    for (int i = 0; i < nw; i++) { /* the writes share the time of the files */
        g->stats[writes[i]].seconds += tw / nw;
        g->stats[writes[i]].calls++;
    }
    free(sw);
    strips_free(&st);
    return r;
}

uint64_t internal_graph_strip_need(nprfx_graph *g, int write, int frame, int rows,
                                   nprfx_result *err)
{
    strips st;
    int *group = malloc((size_t)g->count * sizeof *group);
    if (!group) {
        *err = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        return 0;
    }
    int nw = internal_graph_strip_group(g, write, group);
    *err = strips_prepare(g, group, nw, frame, &st);
    if (*err) {
        free(group);
        return 0;
    }
    /* As if every chain node's strip were held at once (most go back before the next renders):
     * its rows, the channel selections its inputs pack, and for a read the plate before its
     * motion channels are appended and one block of 64 rows it decodes. */
    const uint64_t w = (uint64_t)nprfx_rect_width(st.frame),
                   fh = (uint64_t)nprfx_rect_height(st.frame);
    uint64_t need = 0, packed = 0;
    for (int i = 0; i < st.n; i++) {
        const snode *s = &st.s[i];
        uint64_t h = (uint64_t)rows + 2u * (uint64_t)s->margin;
        if (h > fh) h = fh;
        uint64_t ch = (uint64_t)s->channels + (uint64_t)s->in_channels;
        if (s->rr) ch += (uint64_t)s->shape.nchannels * (1u + (64u + h - 1) / h);
        need += w * h * ch * sizeof(float);
    }
    for (int i = 0; i < nw; i++) /* a write's packed rows (one at a time) */
        if (st.s[st.slot[g->nodes[group[i]].inputs[0].src]].channels > 0) {
            const snode *src = &st.s[st.slot[g->nodes[group[i]].inputs[0].src]];
            uint64_t b = w * (uint64_t)(rows < (int)fh ? rows : (int)fh) * (uint64_t)src->channels *
                         sizeof(float);
            if (b > packed) packed = b;
        }
    need += packed;
    strips_free(&st);
    free(group);
    return need;
}
