/* nprfx graph engine — the graph's outputs: write nodes (EXR and preview through temporary names,
 * never onto one of the graph's inputs), rendering a frame, and the small queries the runner and
 * bench use. */
#define _DEFAULT_SOURCE
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nprfx/graph.h"
#include "graph_cache.h"
#include "graph_eval.h"
#include "graph_files.h"
#include "graph_frames.h"
#include "graph_memory.h"
#include "graph_aovs.h"
#include "graph_model.h"
#include "graph_names.h"
#include "graph_plan.h"
#include "graph_resolve.h"
#include "graph_strips.h"
#include "nprfx/channels.h"
#include "nprfx/exec.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "nprfx/nprfx.h"
#include "nprfx/seq.h"
#include "engine_util.h"

/* Index list of the channels a preview shows: R,G,B,A when present, else the first <= 4. */
static nprfx_result preview_view(nprfx_graph *g, const nprfx_image *im, char **names,
                                 nprfx_image *view, float **scratch)
{
    int idx[4];
    int k = nprfx_channels_from_hint((const char *const *)names, im->channels,
                                     "R,G,B,A|R,G,B|Combined.RGBA|Combined.RGB", idx, 4);
    if (k < 0) {
        k = im->channels < 4 ? im->channels : 3;
        for (int c = 0; c < k; c++)
            idx[c] = c;
    }
    nprfx_result r = nprfx_image_alloc(g->ctx, im->bounds, k, view);
    if (r) return r;
    for (int y = im->bounds.y0; y < im->bounds.y1; y++)
        for (int x = im->bounds.x0; x < im->bounds.x1; x++) {
            const float *s = nprfx_image_at(im, x, y);
            float *d = nprfx_image_at(view, x, y);
            for (int c = 0; c < k; c++)
                d[c] = s[idx[c]];
        }
    *scratch = view->data;
    return NPRFX_OK;
}

/* A write node's files at one frame: the EXR (item 0) and its preview (item 1). */
typedef struct write_files {
    nprfx_graph *g;
    gnode *n;
    const char *path, *preview;
    const nprfx_image *view, *pv;
    const char *const *names;
    nprfx_write_options wo;
    const nprfx_rect *display;
    nprfx_result r[2];
} write_files;

static void write_file(void *user, int begin, int end, int worker)
{
    (void)worker;
    write_files *wf = user;
    const gnode *n = wf->n;
    for (int i = begin; i < end; i++) {
        if (i == 0) {
            wf->r[0] = wf->g->io.write(n->ctx, wf->path, wf->view, wf->names, wf->display, &wf->wo);
        } else {
            nprfx_preview_options po = {sizeof po,  wf->g->ocio, n->colorspace,
                                        n->display, n->view,     n->raw};
            wf->r[1] = wf->g->io.write_preview(n->ctx, wf->preview, wf->pv, &po);
        }
    }
}

/* Write node `node` at frame; files == 0 only evaluates its input (bench-graph's compute time
 * without the file I/O). */
static nprfx_result write_node(nprfx_graph *g, int node, int frame, int files)
{
    gnode *n = &g->nodes[node];
    centry *e;
    nprfx_result r = internal_graph_eval(g, n->inputs[0].src, frame, &e);
    if (r) return r;
    if (!files) {
        internal_graph_consumed(g, e);
        return NPRFX_OK;
    }
    double t0 = engine_now(); /* --stats: the write's own time, not its input's */
    e->pins++;
    nprfx_image view, scratch;
    memset(&scratch, 0, sizeof scratch);
    r = internal_graph_select_input(g, n, 0, e, &view, &scratch);
    char **names = e->names;
    char **sel_names = NULL;
    if (!r && n->inputs[0].sel) {
        /* names of the selected channels, in selection order */
        int idx[256], amb;
        char bad[64];
        int k = nprfx_channels_select((const char *const *)e->names, e->im.channels,
                                      n->inputs[0].sel, idx, 256, bad, sizeof bad, &amb);
        sel_names = calloc((size_t)(k > 0 ? k : 1), sizeof *sel_names);
        for (int c = 0; sel_names && c < k; c++)
            sel_names[c] = e->names[idx[c]];
        names = sel_names;
    }
    char path[4096];
    if (!r) {
        internal_graph_resolve_path(g, g->out_dir, n->path, frame, path, sizeof path);
        r = internal_graph_check_not_input(g, n, path, frame);
    }
    /* A plate as read keeps each channel's file type (uint ids stay uint, half stays half); a
     * node's result is float, or half with "half". Windows and pixel aspect go back as read. */
    unsigned char types[256];
    int have_types = 0;
    if (!r && e->meta.types) {
        int idx[256], count = 0;
        r = internal_graph_input_channels(g, n, 0, (const char *const *)e->names, e->im.channels,
                                          idx, &count);
        for (int c = 0; !r && c < count && c < 256; c++)
            types[c] = e->meta.types[idx[c]];
        have_types = !r;
    }
    /* The EXR and its preview are written side by side, each on a worker of the run's executor:
     * both spend their time compressing (zlib), each on one core. */
    write_files wf;
    memset(&wf, 0, sizeof wf);
    nprfx_image pv;
    memset(&pv, 0, sizeof pv);
    float *pscratch = NULL;
    char ppath[4096];
    if (!r) {
        wf.g = g;
        wf.n = n;
        wf.path = path;
        wf.view = &view;
        wf.names = (const char *const *)names;
        wf.wo =
            (nprfx_write_options){sizeof wf.wo, n->compression ? n->compression : "zip", n->half};
        wf.wo.types = have_types ? types : NULL;
        wf.wo.pixel_aspect = e->meta.pixel_aspect;
        wf.display = nprfx_rect_empty(e->meta.display) ? NULL : &e->meta.display;
    }
    if (!r && n->preview) {
        internal_graph_resolve_path(g, g->out_dir, n->preview, frame, ppath, sizeof ppath);
        r = internal_graph_check_not_input(g, n, ppath, frame);
        if (!r) r = preview_view(g, &view, names, &pv, &pscratch);
        wf.preview = ppath;
        wf.pv = &pv;
    }
    if (!r) {
        nprfx_parallel_for(nprfx_context_executor(g->ctx), n->preview ? 2 : 1, 1, write_file, &wf);
        r = wf.r[0] ? wf.r[0] : wf.r[1];
    }
    free(pscratch);
    free(sel_names);
    internal_graph_frame_release(g, &scratch);
    e->pins--;
    if (!r) internal_graph_consumed(g, e);
    double el = engine_now() - t0;
    g->stats[node].seconds += el;
    g->stats[node].calls++;
    g->child_seconds += el;
    return r;
}

static nprfx_result render_frame(nprfx_graph *g, int frame, int files, int *written)
{
    *written = 0;
    nprfx_result r = internal_graph_prepare(g, frame);
    if (!r) r = internal_graph_plan_build(g);
    internal_graph_frame_begin(g, frame);
    int *group = NULL;
    for (int i = 0; !r && i < g->count; i++) {
        if (g->nodes[i].kind != GK_WRITE) continue;
        /* Strips where the plan chose them (a graph over the memory limit, or --strip-rows):
         * the writes whose chains share nodes go together, from the first of them. */
        if (files && g->strip_rows > 0 && internal_graph_strips_possible(g, i, NULL, 0)) {
            if (!group && !(group = malloc((size_t)g->count * sizeof *group))) {
                r = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
                break;
            }
            int nw = internal_graph_strip_group(g, i, group);
            if (group[0] == i) r = internal_graph_write_strips(g, group, nw, frame);
        } else {
            r = write_node(g, i, frame, files);
        }
        if (!r) (*written)++;
    }
    free(group);
    /* What the next frame will not read goes now, not when the byte bound is reached. */
    internal_graph_frame_sweep(g);
    return r;
}

nprfx_result nprfx_graph_render_frame(nprfx_graph *g, int frame, int *written)
{
    return render_frame(g, frame, 1, written);
}

nprfx_result nprfx_graph_compute_frame(nprfx_graph *g, int frame)
{
    int n;
    return render_frame(g, frame, 0, &n);
}

void nprfx_graph_describe_outputs(const nprfx_graph *g, char *buf, size_t n)
{
    buf[0] = 0;
    for (int i = 0; i < g->count; i++) {
        const gnode *w = &g->nodes[i];
        if (w->kind != GK_WRITE) continue;
        size_t len = strlen(buf);
        const char *dir = g->out_dir ? g->out_dir : "";
        const char *sep = dir[0] ? "/" : "";
        if (w->preview)
            snprintf(buf + len, n - len, "  %s%s%s  (previews %s%s%s)\n", dir, sep, w->path, dir,
                     sep, w->preview);
        else
            snprintf(buf + len, n - len, "  %s%s%s\n", dir, sep, w->path);
    }
}

long long nprfx_graph_take_render_items(nprfx_graph *g)
{
    long long n = g->render_items;
    g->render_items = 0;
    return n;
}

double nprfx_graph_take_render_bytes(nprfx_graph *g)
{
    double b = g->render_bytes;
    g->render_bytes = 0;
    return b;
}

double nprfx_graph_take_render_cpu_seconds(nprfx_graph *g)
{
    double s = g->render_cpu_seconds;
    g->render_cpu_seconds = 0;
    return s;
}

double nprfx_graph_take_render_seconds(nprfx_graph *g)
{
    double s = g->render_seconds;
    g->render_seconds = 0;
    return s;
}

int nprfx_graph_write_count(const nprfx_graph *g)
{
    int writes = 0;
    for (int i = 0; i < g->count; i++)
        writes += g->nodes[i].kind == GK_WRITE;
    return writes;
}

int nprfx_graph_has_node(const nprfx_graph *g, const char *name)
{
    return internal_graph_find_node(g, name) >= 0;
}

nprfx_result nprfx_graph_eval(nprfx_graph *g, const char *name, int frame, nprfx_image *out,
                              const char *const **names)
{
    int i = internal_graph_find_node(g, name);
    if (i < 0 || g->nodes[i].kind == GK_WRITE)
        return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_NODE, "the graph has no node '%s' to evaluate",
                           name);
    /* The previous call's view is no longer promised: sweep as after a frame, then begin one. */
    nprfx_result r = internal_graph_prepare(g, frame);
    if (!r) r = internal_graph_plan_build(g);
    if (r) return r;
    internal_graph_frame_sweep(g);
    internal_graph_frame_begin(g, frame);
    centry *e;
    /* A plate asked for by name is whole: a trimmed one kept for a temporal reader goes. */
    int plate = g->nodes[i].kind == GK_READ || g->nodes[i].kind == GK_SYNTH;
    if (plate && (e = internal_graph_cache_find(g, i, frame)) && !e->pins)
        internal_graph_cache_drop(g, e);
    g->external = plate;
    r = internal_graph_eval(g, i, frame, &e);
    g->external = 0;
    if (!r) *out = e->im;
    if (!r && names) *names = (const char *const *)e->names;
    return r;
}
