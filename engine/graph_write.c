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
#include "graph_write_jobs.h"
#include "nprfx/channels.h"
#include "nprfx/exec.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "nprfx/nprfx.h"
#include "nprfx/seq.h"
#include "engine_util.h"

/* Index list of the channels a preview shows: R,G,B,A when present, else the first <= 4. */
static nprfx_result preview_view(nprfx_graph *g, const nprfx_image *im, char **names,
                                 nprfx_image *view)
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
    return NPRFX_OK;
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
    write_job *j = calloc(1, sizeof *j);
    if (!j) return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    j->started = engine_now(); /* --stats: the write's own time, not its input's */
    j->node = node;
    j->frame = frame;
    j->e = e;
    e->pins++;
    r = internal_graph_select_input(g, n, 0, e, &j->view, &j->scratch);
    j->names = (const char *const *)e->names;
    if (!r && n->inputs[0].sel) {
        /* names of the selected channels, in selection order */
        int idx[256], amb;
        char bad[64];
        int k = nprfx_channels_select((const char *const *)e->names, e->im.channels,
                                      n->inputs[0].sel, idx, 256, bad, sizeof bad, &amb);
        j->sel_names = calloc((size_t)(k > 0 ? k : 1), sizeof *j->sel_names);
        for (int c = 0; j->sel_names && c < k; c++)
            j->sel_names[c] = e->names[idx[c]];
        j->names = (const char *const *)j->sel_names;
    }
    if (!r) {
        internal_graph_resolve_path(g, g->out_dir, n->path, frame, j->path, sizeof j->path);
        r = internal_graph_check_not_input(g, n, j->path, frame);
    }
    /* A plate as read keeps each channel's file type (uint ids stay uint, half stays half); a
     * node's result is float, or half with "half". Windows and pixel aspect go back as read. */
    j->wo = (nprfx_write_options){sizeof j->wo, n->compression ? n->compression : "zip", n->half};
    if (!r && e->meta.types) {
        int idx[256], count = 0;
        r = internal_graph_input_channels(g, n, 0, (const char *const *)e->names, e->im.channels,
                                          idx, &count);
        for (int c = 0; !r && c < count && c < 256; c++)
            j->types[c] = e->meta.types[idx[c]];
        if (!r) j->wo.types = j->types;
    }
    j->wo.pixel_aspect = e->meta.pixel_aspect;
    j->display = e->meta.display;
    j->has_display = !nprfx_rect_empty(e->meta.display);
    if (!r && n->preview) {
        internal_graph_resolve_path(g, g->out_dir, n->preview, frame, j->ppath, sizeof j->ppath);
        r = internal_graph_check_not_input(g, n, j->ppath, frame);
        if (!r) r = preview_view(g, &j->view, (char **)j->names, &j->pv);
        j->preview = !r;
    }
    double el = engine_now() - j->started;
    if (!r) {
        internal_graph_consumed(g, e);
        /* The EXR and its preview are written side by side, each on a core: both spend their
         * time compressing (zlib). */
        r = internal_graph_write_job_start(g, j);
    } else {
        internal_graph_frame_release(g, &j->scratch);
        free(j->pv.data);
        free(j->sel_names);
        e->pins--;
        free(j);
    }
    g->child_seconds += el;
    return r;
}

static nprfx_result render_frame(nprfx_graph *g, int frame, int files, int *written)
{
    *written = 0;
    nprfx_result r = internal_graph_frame_ok(g, frame);
    if (!r) r = internal_graph_prepare(g, frame);
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
    nprfx_result r = internal_graph_frame_ok(g, frame);
    if (!r) r = internal_graph_prepare(g, frame);
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
