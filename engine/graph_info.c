/* nprfx graph engine — what a graph holds, for front ends that translate it (nprfx/graph.h:
 * nprfx_graph_node and the resolution it shares with the evaluation). */
#include <stddef.h>
#include <string.h>

#include "graph_aovs.h"
#include "graph_extras.h"
#include "graph_model.h"
#include "graph_names.h"
#include "graph_resolve.h"
#include "nprfx/graph.h"

int nprfx_graph_node_count(const nprfx_graph *g)
{
    return g ? (g->flows_wired ? g->count : g->visible) : 0;
}

int nprfx_graph_node_index(const nprfx_graph *g, const char *name)
{
    return g && name ? internal_graph_find_node(g, name) : -1;
}

nprfx_result nprfx_graph_node(const nprfx_graph *g, int i, nprfx_graph_node_info *out)
{
    if (!g || !out || i < 0 || i >= g->count) return NPRFX_ERR_INVALID_ARGUMENT;
    const gnode *n = &g->nodes[i];
    nprfx_graph_node_info v;
    memset(&v, 0, sizeof v);
    v.size = sizeof v;
    v.name = n->name;
    v.kind = (int)n->kind;
    v.desc = n->desc;
    v.ninputs = n->ninputs;
    v.inputs = n->inputs;
    v.params = n->params;
    v.param_text = (const char *const *)n->param_text;
    v.ctx = n->ctx;
    v.path = n->path;
    v.preview = n->preview;
    v.colorspace = n->colorspace;
    v.vectors = n->vectors;
    v.compression = n->compression;
    v.scene = n->scene;
    v.display = n->display;
    v.view = n->view;
    v.part = n->part;
    v.read_view = n->read_view;
    v.half = n->half;
    v.raw = n->raw;
    v.width = n->width;
    v.height = n->height;
    v.read_channels = n->read_channels;
    v.file_channels = n->file_channels;
    /* An older, shorter struct gets the fields it has. */
    size_t size = out->size && out->size < sizeof v ? out->size : sizeof v;
    memcpy(out, &v, size);
    out->size = size;
    return NPRFX_OK;
}

nprfx_context *nprfx_graph_context(const nprfx_graph *g)
{
    return g ? g->ctx : NULL;
}

const char *nprfx_graph_base_dir(const nprfx_graph *g)
{
    return g ? g->base_dir : NULL;
}

void nprfx_graph_resolve_path(const nprfx_graph *g, const char *dir, const char *pattern, int frame,
                              char *buf, size_t n)
{
    internal_graph_resolve_path(g, dir, pattern, frame, buf, n);
}

nprfx_result nprfx_graph_input_channels(nprfx_graph *g, int node, int k, const char *const *names,
                                        int nc, int *idx, int *count)
{
    if (!g || node < 0 || node >= g->count || k < 0 || k >= g->nodes[node].ninputs)
        return NPRFX_ERR_INVALID_ARGUMENT;
    return internal_graph_input_channels(g, &g->nodes[node], k, names, nc, idx, count);
}

nprfx_result nprfx_graph_settle(nprfx_graph *g, int frame)
{
    return internal_graph_prepare(g, frame);
}

const char *nprfx_graph_read_vectors(const nprfx_graph *g, int node)
{
    if (!g || node < 0 || node >= g->count) return NULL;
    const nprfx_aov_vectors *v = internal_graph_vectors(&g->nodes[node]);
    return v ? v->name : NULL;
}

int nprfx_graph_read_decodes(const nprfx_graph *g, int node)
{
    if (!g || node < 0 || node >= g->count) return 0;
    const gnode *n = &g->nodes[node];
    return n->kind == GK_READ ? (n->crypto != NULL) + (n->depth_inverse != NULL) : 0;
}

int nprfx_graph_read_extras(const nprfx_graph *g, int node, const char **names, int max)
{
    if (!g || node < 0 || node >= g->count) return 0;
    const gnode *n = &g->nodes[node];
    int count = internal_graph_extra_count(n);
    for (int k = 0; k < count && k < max; k++)
        names[k] = internal_graph_extra_name(n, k);
    return count;
}

const char *nprfx_graph_motion_name(int k)
{
    return k >= 0 && k < 4 ? internal_graph_motion_names[k] : NULL;
}

nprfx_result nprfx_graph_motion_sources(nprfx_graph *g, int node, const char *file,
                                        const char *const *names, int nc, int *idx, double *sign)
{
    if (!g || node < 0 || node >= g->count || g->nodes[node].kind != GK_READ)
        return NPRFX_ERR_INVALID_ARGUMENT;
    return internal_graph_motion_sources(g, &g->nodes[node], file, names, nc, idx, sign);
}
