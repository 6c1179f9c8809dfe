/* nprfx graph engine — a graph's plates: read nodes (the channels the graph uses, the motion
 * channels a convention appends, colour conversion; whole frames or a strip of rows) and synth
 * nodes. */
#define _DEFAULT_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "nprfx/exec.h"
#include "nprfx/graph.h"
#include "graph_extras.h"
#include "graph_frames.h"
#include "graph_memory.h"
#include "graph_model.h"
#include "graph_plan.h"
#include "graph_read.h"
#include "graph_resolve.h"
#include "graph_variant.h"
#include "nprfx/channels.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "nprfx/io.h"
#include "engine_util.h"

/* The channels the read appends (graph_extras.c), after the plate's own. */
static nprfx_result add_extra_channels(nprfx_graph *g, gnode *n, const char *file,
                                       nprfx_plate *plate)
{
    gextra x;
    nprfx_result r =
        internal_graph_extras(g, n, file, (const char *const *)plate->names, plate->nchannels, &x);
    if (r || !x.count) return r;
    int nc = plate->nchannels, nn = nc + x.count;
    size_t npix =
        (size_t)nprfx_rect_width(plate->bounds) * (size_t)nprfx_rect_height(plate->bounds);
    float *px = malloc(npix * (size_t)nn * sizeof(float));
    char **names = realloc(plate->names, (size_t)nn * sizeof *names);
    if (!px || !names) {
        free(px);
        if (names) plate->names = names;
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory reading %s", file);
    }
    plate->names = names;
    for (int k = 0; k < x.count; k++)
        names[nc + k] = engine_strdup(internal_graph_extra_name(n, k));
    /* A band of rows at a time, copied then filled while it is still in the cache. */
    const size_t w = (size_t)nprfx_rect_width(plate->bounds);
    const int h = nprfx_rect_height(plate->bounds), band_rows = 16;
    for (int y = 0; y < h; y += band_rows) {
        const int y1 = y + band_rows < h ? y + band_rows : h;
        const float *src = plate->pixels + (size_t)y * w * (size_t)nc;
        float *dst = px + (size_t)y * w * (size_t)nn;
        for (size_t p = 0; p < (size_t)(y1 - y) * w; p++)
            memcpy(dst + p * (size_t)nn, src + p * (size_t)nc, (size_t)nc * sizeof(float));
        nprfx_rect band = {plate->bounds.x0, plate->bounds.y0 + y, plate->bounds.x1,
                           plate->bounds.y0 + y1};
        internal_graph_extra_fill(&x, src, nc, dst, nn, band, plate->display);
    }
    free(plate->pixels);
    plate->pixels = px;
    plate->nchannels = nn;
    return NPRFX_OK;
}

static int push_want(gnode *n, char *sel)
{
    if ((n->nwants & (n->nwants - 1)) == 0) { /* 0, 1, 2, 4, ...: grow to the next power */
        char **w = realloc(n->wants, (size_t)(n->nwants ? 2 * n->nwants : 1) * sizeof *w);
        if (!w) return 0;
        n->wants = w;
    }
    n->wants[n->nwants++] = sel;
    return 1;
}

/* The channels the graph names on each read node: every reference's selection and the vectors
 * convention's channels, which pick the part of a multi-part file when none is given. One pass
 * over all references, at the first read. */
static nprfx_result gather_wants(nprfx_graph *g)
{
    for (int i = 0; i < g->count; i++) {
        gnode *n = &g->nodes[i];
        n->wants_known = 1;
        for (int k = 0; k < n->ninputs; k++) {
            const gref *ref = &n->inputs[k];
            if (ref->src < 0 || !ref->sel || g->nodes[ref->src].kind != GK_READ) continue;
            if (!push_want(&g->nodes[ref->src], ref->sel))
                return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        }
        /* what the appended channels are made of */
        const char *w;
        for (int k = 0; n->kind == GK_READ && (w = internal_graph_extra_want(n, k)); k++)
            if (!push_want(n, (char *)w))
                return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    return NPRFX_OK;
}

typedef struct read_pick {
    nprfx_graph *g;
    int node;
} read_pick;

static int pick_channels(void *user, const char *const *names, int n, int *pick)
{
    const read_pick *rp = user;
    int m = internal_graph_read_pick(rp->g, rp->node, names, n, pick);
    /* what --stats says the read takes of its files */
    gnode *nd = &rp->g->nodes[rp->node];
    size_t len = 1;
    for (int k = 0; k < (m > 0 ? m : n); k++)
        len += strlen(names[m > 0 ? pick[k] : k]) + 1;
    char *list = malloc(len);
    if (list) {
        list[0] = 0;
        for (int k = 0; k < (m > 0 ? m : n); k++) {
            if (k) strcat(list, ",");
            strcat(list, names[m > 0 ? pick[k] : k]);
        }
        free(nd->read_channels);
        nd->read_channels = list;
        nd->file_channels = n;
    }
    return m;
}

/* A read's note or warning, through the graph's notices. */
static void read_notice(nprfx_graph *g, const gnode *n, const char *note, int warning)
{
    if (!note || !g->notice) return;
    char msg[4600];
    snprintf(msg, sizeof msg, "%s: read '%s': %s", warning ? "warning" : "note", n->name, note);
    g->notice(g->notice_user, msg);
}

/* The read's note on parts and views, once per node. */
static void plate_note(nprfx_graph *g, gnode *n, const char *note, int warning)
{
    if (!n->noted) read_notice(g, n, note, warning);
    n->noted = 1;
}

/* R,G,B of im (names: its channels) to scene-linear from the read's colour space, if it has one. */
static nprfx_result plate_colour(nprfx_graph *g, gnode *n, const char *file, nprfx_image *im,
                                 const char *const *names)
{
    const char *from = internal_graph_colorspace(n);
    int idx[3], amb;
    char bad[64];
    if (!from ||
        nprfx_channels_select(names, im->channels, "R,G,B", idx, 3, bad, sizeof bad, &amb) != 3 ||
        idx[1] != idx[0] + 1 || idx[2] != idx[0] + 2)
        return NPRFX_OK;
    nprfx_image rgb = *im;
    rgb.data = im->data + idx[0];
    rgb.channels = 3;
    nprfx_context *fctx = NULL; /* the file's name before what OCIO says */
    nprfx_result r = nprfx_context_create_scoped(n->ctx, file, &fctx);
    if (!r) r = g->io.convert_colorspace(fctx, &rgb, from, "scene_linear", g->ocio);
    nprfx_context_destroy(fctx);
    return r;
}

/* What a read makes of the channels it read, the same for a whole plate and a strip of rows:
 * the note on parts and views (once per node), the motion channels, the colour conversion. */
static nprfx_result finish_plate(nprfx_graph *g, gnode *n, const char *file, nprfx_plate *plate)
{
    plate_note(g, n, plate->note, plate->note_is_warning);
    nprfx_result r = add_extra_channels(g, n, file, plate);
    if (r) return r;
    nprfx_image im = nprfx_plate_view(plate, 0, plate->nchannels);
    return plate_colour(g, n, file, &im, (const char *const *)plate->names);
}

static nprfx_read_options read_options_of(gnode *n, read_pick *rp)
{
    nprfx_read_options ro;
    memset(&ro, 0, sizeof ro);
    ro.size = sizeof ro;
    ro.part = n->part;
    ro.view = n->read_view;
    ro.want = (const char *const *)n->wants;
    ro.nwant = n->nwants;
    /* Only the channels the graph uses are read (the plan picks them from the names the read
     * would deliver): a renderer's plate has 23-56, a graph reads a dozen. */
    ro.pick = pick_channels;
    ro.pick_user = rp;
    return ro;
}

nprfx_result internal_graph_read_rows_open(nprfx_graph *g, int node, int frame, char *file,
                                           size_t n, nprfx_plate *shape, nprfx_row_reader **rr)
{
    gnode *nd = &g->nodes[node];
    internal_graph_resolve_path(g, g->base_dir, nd->path, frame, file, n);
    nprfx_result r = nd->wants_known ? NPRFX_OK : gather_wants(g);
    if (r) return r;
    read_pick rp = {g, node};
    nprfx_read_options ro = read_options_of(nd, &rp);
    return g->io.rows_open(nd->ctx, file, &ro, shape, rr);
}

nprfx_result internal_graph_read_rows(nprfx_graph *g, int node, const char *file,
                                      nprfx_row_reader *rr, const nprfx_plate *shape, int y0,
                                      int y1, nprfx_plate *out)
{
    gnode *n = &g->nodes[node];
    memset(out, 0, sizeof *out);
    int w = nprfx_rect_width(shape->bounds), nc = shape->nchannels;
    out->bounds = nprfx_rect_make(shape->bounds.x0, y0, shape->bounds.x1, y1);
    out->display = shape->display;
    out->pixel_aspect = shape->pixel_aspect;
    out->pixels = malloc((size_t)w * (size_t)(y1 - y0) * (size_t)nc * sizeof(float));
    out->names = internal_graph_names_dup((const char *const *)shape->names, nc);
    if (!out->pixels || !out->names) {
        free(out->pixels);
        for (int c = 0; out->names && c < nc; c++)
            free(out->names[c]);
        free(out->names);
        memset(out, 0, sizeof *out);
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory reading %s", file);
    }
    out->nchannels = nc;
    /* The read's note on parts and views goes out with its first strip, as with a whole plate. */
    if (!n->noted && shape->note) {
        out->note = engine_strdup(shape->note);
        out->note_is_warning = shape->note_is_warning;
    }
    nprfx_result r = g->io.rows_read(n->ctx, rr, y0, y1, out->pixels);
    if (!r) r = finish_plate(g, n, file, out);
    if (r) nprfx_plate_free(out);
    return r;
}

/* An EXR plate read straight into a frame of the pool, a band of rows at a time through a small
 * scratch, each band copied beside the channels the read appends while it is in the cache. A
 * whole read into memory of its own cost a fresh mapping of the plate every frame (100+ MB at
 * 1080p: a fifth of the read in page faults), another for the appended channels, and a copy
 * each. Three steps, so that the middle one, all of the decoding, may run on another thread
 * while the current frame computes (graph_prefetch.c): open (the header, the frame from the
 * pool), fill (the pixels: touches nothing of the graph), finish (names, note, colour). */
nprfx_result internal_graph_pooled_open(nprfx_graph *g, int node, int frame, int spare,
                                        pooled_read *p, int *ok)
{
    gnode *n = &g->nodes[node];
    memset(p, 0, sizeof *p);
    *ok = 0;
    p->node = node;
    p->frame = frame;
    internal_graph_resolve_path(g, g->base_dir, n->path, frame, p->file, sizeof p->file);
    nprfx_result r = n->wants_known ? NPRFX_OK : gather_wants(g);
    if (r) return r;
    read_pick rp = {g, node};
    nprfx_read_options ro = read_options_of(n, &rp);
    /* a prefetch says nothing: the frame's own read says what is wrong, when it comes */
    nprfx_context *ctx = spare ? NULL : n->ctx;
    r = g->io.rows_open(ctx, p->file, &ro, &p->shape, &p->rr);
    if (r == NPRFX_ERR_UNSUPPORTED || (r && spare)) return NPRFX_OK;
    if (r) return r;
    p->nc = p->shape.nchannels;
    r = internal_graph_extras(g, n, p->file, (const char *const *)p->shape.names, p->nc, &p->x);
    p->nn = p->nc + (r ? 0 : p->x.count);
    char what[600];
    snprintf(what, sizeof what, "node '%s': plate", n->name);
    if (!r)
        r = spare ? internal_graph_frame_alloc_spare(g, node, p->shape.bounds, p->nn, &p->im)
                  : internal_graph_frame_alloc_unset(g, node, what, p->shape.bounds, p->nn, &p->im);
    if (r) {
        g->io.rows_close(p->rr);
        nprfx_plate_free(&p->shape);
        memset(p, 0, sizeof *p);
        return spare ? NPRFX_OK : r;
    }
    p->io = g->io;
    *ok = 1;
    return NPRFX_OK;
}

/* Rows [y0, y1) (offsets in the data window) of p's plate into its frame through rr. */
static nprfx_result fill_rows(pooled_read *p, nprfx_row_reader *rr, nprfx_context *ctx, int y0,
                              int y1)
{
    const int w = nprfx_rect_width(p->shape.bounds);
    const int band_rows = 32, nc = p->nc, nn = p->nn;
    float *band = malloc((size_t)w * band_rows * (size_t)nc * sizeof *band);
    nprfx_result r =
        band ? NPRFX_OK
             : nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory reading %s", p->file);
    for (int y = y0; !r && y < y1; y += band_rows) {
        const int ye = y + band_rows < y1 ? y + band_rows : y1;
        nprfx_rect b = {p->shape.bounds.x0, p->shape.bounds.y0 + y, p->shape.bounds.x1,
                        p->shape.bounds.y0 + ye};
        if ((r = p->io.rows_read(ctx, rr, b.y0, b.y1, band))) break;
        float *dst = nprfx_image_at(&p->im, b.x0, b.y0);
        for (size_t k = 0; k < (size_t)(ye - y) * (size_t)w; k++)
            memcpy(dst + k * (size_t)nn, band + k * (size_t)nc, (size_t)nc * sizeof(float));
        if (nn > nc) internal_graph_extra_fill(&p->x, band, nc, dst, nn, b, p->shape.display);
    }
    free(band);
    return r;
}

void internal_graph_pooled_fill(pooled_read *p, nprfx_context *ctx)
{
    nprfx_result r = fill_rows(p, p->rr, ctx, 0, nprfx_rect_height(p->shape.bounds));
    /* the read's note on parts and views */
    if (!r) r = p->io.rows_note(ctx, p->rr, &p->note, &p->warning);
    p->io.rows_close(p->rr);
    p->rr = NULL;
    p->r = r;
}

/* A plate the frame waits for (nothing decoded it ahead: the first frame, a frame out of order)
 * is decoded by every worker of the executor, a band of rows each through a reader of its own,
 * instead of by one core while the others wait. Bands start at multiples of 64 rows, whole
 * chunks of every EXR compression, so no chunk is decoded twice. */
typedef struct band_fill {
    pooled_read *p;
    nprfx_row_reader **rr;
    nprfx_context *ctx;
    int rows; /* per band */
    nprfx_result r[64];
} band_fill;

static void fill_band(void *user, int begin, int end, int worker)
{
    (void)worker;
    band_fill *bf = user;
    const int h = nprfx_rect_height(bf->p->shape.bounds);
    for (int i = begin; i < end; i++) {
        int y0 = i * bf->rows, y1 = y0 + bf->rows < h ? y0 + bf->rows : h;
        bf->r[i] = y0 < h ? fill_rows(bf->p, bf->rr[i], bf->ctx, y0, y1) : NPRFX_OK;
    }
}

static void pooled_fill_now(nprfx_graph *g, pooled_read *p)
{
    gnode *n = &g->nodes[p->node];
    const nprfx_executor *ex = nprfx_context_executor(g->ctx);
    const int h = nprfx_rect_height(p->shape.bounds);
    int bands = nprfx_executor_workers(ex);
    if (bands > 64) bands = 64;
    int rows = ((h + bands - 1) / bands + 63) / 64 * 64;
    bands = rows > 0 ? (h + rows - 1) / rows : 1;
    if (bands < 2) {
        internal_graph_pooled_fill(p, n->ctx);
        return;
    }
    band_fill bf;
    memset(&bf, 0, sizeof bf);
    nprfx_row_reader *rr[64] = {p->rr};
    bf.p = p;
    bf.rr = rr;
    bf.ctx = n->ctx;
    bf.rows = rows;
    nprfx_result r = NPRFX_OK;
    /* the other bands' readers, opened here: opening one names the channels in --stats */
    for (int i = 1; !r && i < bands; i++) {
        read_pick rp = {g, p->node};
        nprfx_read_options ro = read_options_of(n, &rp);
        nprfx_plate shape;
        memset(&shape, 0, sizeof shape);
        r = g->io.rows_open(n->ctx, p->file, &ro, &shape, &rr[i]);
        if (!r && shape.nchannels != p->nc)
            r = nprfx_error(n->ctx, NPRFX_ERR_IO, "'%s' changed while it was read", p->file);
        nprfx_plate_free(&shape);
    }
    if (!r) nprfx_parallel_for(ex, bands, 1, fill_band, &bf);
    for (int i = 0; !r && i < bands; i++)
        r = bf.r[i];
    /* the read's note on parts and views (every band's is the same) */
    if (!r) r = p->io.rows_note(n->ctx, rr[0], &p->note, &p->warning);
    for (int i = 0; i < bands; i++)
        if (rr[i]) p->io.rows_close(rr[i]);
    p->rr = NULL;
    p->r = r;
}

void internal_graph_pooled_drop(nprfx_graph *g, pooled_read *p)
{
    if (p->rr) g->io.rows_close(p->rr);
    if (p->im.data) internal_graph_frame_release(g, &p->im);
    free(p->note);
    nprfx_plate_free(&p->shape);
    memset(p, 0, sizeof *p);
}

nprfx_result internal_graph_pooled_finish(nprfx_graph *g, pooled_read *p, nprfx_image *im,
                                          char ***names, gmeta *meta)
{
    gnode *n = &g->nodes[p->node];
    const int nc = p->nc, nn = p->nn;
    nprfx_result r = p->r;
    char **all = r ? NULL : calloc((size_t)nn, sizeof *all);
    if (!r && !all) r = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    for (int c = 0; !r && c < nn; c++)
        if (!(all[c] =
                  engine_strdup(c < nc ? p->shape.names[c] : internal_graph_extra_name(n, c - nc))))
            r = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory reading %s", p->file);
    if (!r) {
        if (p->note)
            plate_note(g, n, p->note, p->warning);
        else
            plate_note(g, n, p->shape.note, p->shape.note_is_warning);
        r = plate_colour(g, n, p->file, &p->im, (const char *const *)all);
    }
    unsigned char *types = r ? NULL : realloc(p->shape.types, (size_t)nn);
    if (types) {
        for (int c = nc; c < nn; c++) /* the appended channels are floats of their own */
            types[c] = NPRFX_PIXEL_FLOAT;
        p->shape.types = NULL;
    }
    if (r) {
        engine_names_free(all, all ? nn : 0);
        internal_graph_pooled_drop(g, p);
        return r;
    }
    *im = p->im;
    p->im.data = NULL;
    *names = all;
    internal_graph_variant_plate(g, im, *names);
    meta->display = p->shape.display;
    meta->pixel_aspect = p->shape.pixel_aspect;
    meta->types = types;
    internal_graph_pooled_drop(g, p);
    return NPRFX_OK;
}

nprfx_result internal_graph_read_plate(nprfx_graph *g, int node, int frame, nprfx_image *im,
                                       char ***names, gmeta *meta, int *pooled)
{
    gnode *n = &g->nodes[node];
    char file[4096];
    internal_graph_resolve_path(g, g->base_dir, n->path, frame, file, sizeof file);
    nprfx_plate plate;
    memset(&plate, 0, sizeof plate);
    nprfx_result r = n->wants_known ? NPRFX_OK : gather_wants(g);
    if (r) return r;
    *pooled = 0;
    if (!g->no_pool) {
        /* decoded already while the frame before computed, or now */
        pooled_read p;
        int ok = 0;
        if (!(r = internal_graph_prefetched(g, node, frame, &p, &ok)) && !ok &&
            !(r = internal_graph_pooled_open(g, node, frame, 0, &p, &ok)) && ok)
            pooled_fill_now(g, &p);
        if (!r && ok) r = internal_graph_pooled_finish(g, &p, im, names, meta);
        /* the next frame's plate decodes while this one computes */
        if (!r) internal_graph_prefetch_next(g, node, frame);
        if (r) return r;
        if (ok) {
            *pooled = 1;
            return NPRFX_OK;
        }
    }
    read_pick rp = {g, node};
    nprfx_read_options ro = read_options_of(n, &rp);
    if ((r = g->io.read(n->ctx, file, &ro, &plate))) return r;
    if ((r = finish_plate(g, n, file, &plate))) {
        nprfx_plate_free(&plate);
        return r;
    }
    im->data = plate.pixels;
    im->channels = plate.nchannels;
    im->pixel_stride = plate.nchannels;
    im->row_stride = (ptrdiff_t)nprfx_rect_width(plate.bounds) * plate.nchannels;
    im->bounds = plate.bounds;
    *names = plate.names;
    internal_graph_variant_plate(g, im, *names);
    meta->display = plate.display;
    meta->pixel_aspect = plate.pixel_aspect;
    /* The appended channels are floats of their own. */
    unsigned char *types = realloc(plate.types, (size_t)plate.nchannels);
    if (types) {
        for (int c = 0; c < plate.nchannels; c++)
            if (c >= plate.nchannels - internal_graph_extra_count(n)) types[c] = NPRFX_PIXEL_FLOAT;
        meta->types = types;
        plate.types = NULL;
    }
    internal_graph_frame_adopt(g, node, im);
    plate.pixels = NULL;
    plate.names = NULL;
    plate.nchannels = 0;
    nprfx_plate_free(&plate);
    return NPRFX_OK;
}

nprfx_result internal_graph_synth_plate(nprfx_graph *g, int node, int frame, nprfx_image *im,
                                        char ***names, gmeta *meta)
{
    gnode *n = &g->nodes[node];
    const char *const *all = nprfx_synth_channel_names();
    int nc = nprfx_synth_channel_count(), pick[1024];
    /* Only the channels the readers take are made (as a read reads only those): the plate is
     * never whole, and unpicked motion is not computed. */
    int count = internal_graph_plate_pick(g, node, all, nc, pick);
    if (count <= 0) {
        count = nc;
        for (int c = 0; c < nc; c++)
            pick[c] = c;
    }
    char what[300];
    snprintf(what, sizeof what, "node '%s': synth frame", n->name);
    nprfx_result r = internal_graph_frame_alloc(
        g, node, what, nprfx_rect_make(0, 0, n->width, n->height), count, im);
    if (r) return r;
    if ((r = nprfx_synth_render_channels(n->ctx, n->scene, frame, pick, count, im))) {
        internal_graph_frame_release(g, im);
        return r;
    }
    const char *picked[1024];
    for (int c = 0; c < count; c++)
        picked[c] = all[pick[c]];
    *names = internal_graph_names_dup(picked, count);
    if (!*names) {
        internal_graph_frame_release(g, im);
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    internal_graph_variant_plate(g, im, *names);
    meta->display = im->bounds;
    meta->pixel_aspect = 1.0f;
    return NPRFX_OK;
}
