/* nprfx graph engine — the files a graph reads and writes: its read patterns and the shot it declares
 * (what nprfx farm checks before it submits a shot in chunks: every chunk must find its plates
 * and see the same shot), the patterns it writes, and the refusal to write over an input. */
#define _DEFAULT_SOURCE /* realpath */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/graph.h"
#include "graph_files.h"
#include "graph_model.h"
#include "graph_resolve.h"

nprfx_result nprfx_graph_read_patterns(const nprfx_graph *g, char ***paths, const char ***nodes,
                                       int *count)
{
    int reads = 0;
    for (int i = 0; i < g->count; i++)
        reads += g->nodes[i].kind == GK_READ && g->nodes[i].path;
    *paths = calloc((size_t)(reads > 0 ? reads : 1), sizeof **paths);
    const char **names = calloc((size_t)(reads > 0 ? reads : 1), sizeof *names);
    *count = 0;
    int ok = *paths && names;
    for (int i = 0; ok && i < g->count; i++) {
        const gnode *n = &g->nodes[i];
        if (n->kind != GK_READ || !n->path) continue;
        const char *dir = g->base_dir;
        int plain = n->path[0] == '/' || !dir || !dir[0] || !strcmp(dir, ".");
        size_t len = strlen(n->path) + (plain ? 0 : strlen(dir) + 1) + 1;
        char *p = malloc(len);
        if (!p) {
            ok = 0;
            break;
        }
        /* Tokens kept: internal_graph_resolve_path expands them, this is the same placement. */
        if (plain)
            snprintf(p, len, "%s", n->path);
        else
            snprintf(p, len, "%s/%s", dir, n->path);
        names[*count] = n->name;
        (*paths)[(*count)++] = p;
    }
    if (!ok) {
        nprfx_graph_output_patterns_free(*paths, *count);
        free(names);
        *paths = NULL;
        *count = 0;
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY,
                           "out of memory listing the graph's reads");
    }
    if (nodes)
        *nodes = names;
    else
        free(names);
    return NPRFX_OK;
}

int nprfx_graph_shot(const nprfx_graph *g, int *first, int *last)
{
    if (!g->frames_text) return 0;
    *first = g->first_frame;
    *last = g->last_frame;
    return 1;
}

/* Refuse to write over a file some read node of the graph takes as input at this frame: inputs
 * are never overwritten, even by a graph that names the same sequence twice. */
nprfx_result internal_graph_check_not_input(nprfx_graph *g, const gnode *w, const char *out,
                                            int frame)
{
    char in[4096], rin[PATH_MAX], rout[PATH_MAX];
    if (!realpath(out, rout)) return NPRFX_OK; /* does not exist yet: cannot be an input */
    for (int i = 0; i < g->count; i++) {
        if (g->nodes[i].kind != GK_READ) continue;
        internal_graph_resolve_path(g, g->base_dir, g->nodes[i].path, frame, in, sizeof in);
        if (realpath(in, rin) && !strcmp(rin, rout))
            return nprfx_error(g->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "node '%s': refusing to overwrite '%s', the input of read node '%s'",
                               w->name, out, g->nodes[i].name);
    }
    return NPRFX_OK;
}

/* pattern relative to the output directory, as internal_graph_resolve_path places a frame's
 * file, with its frame tokens left in; appended to *list (NULL on no memory). */
static int push_output(const nprfx_graph *g, const char *pattern, char ***list, int *count)
{
    if (!pattern || !pattern[0]) return 1;
    const char *dir = g->out_dir;
    int plain = pattern[0] == '/' || !dir || !dir[0] || !strcmp(dir, ".");
    size_t n = strlen(pattern) + (plain ? 0 : strlen(dir) + 1) + 1;
    char *path = malloc(n), **grown = realloc(*list, (size_t)(*count + 1) * sizeof *grown);
    if (grown) *list = grown;
    if (!path || !grown) {
        free(path);
        return 0;
    }
    if (plain)
        snprintf(path, n, "%s", pattern);
    else
        snprintf(path, n, "%s/%s", dir, pattern);
    grown[(*count)++] = path;
    return 1;
}

nprfx_result nprfx_graph_output_patterns(const nprfx_graph *g, char ***paths, int *count)
{
    *paths = NULL;
    *count = 0;
    int ok = 1;
    for (int i = 0; ok && i < g->count; i++) {
        const gnode *n = &g->nodes[i];
        if (n->kind == GK_WRITE) {
            ok = push_output(g, n->path, paths, count) && push_output(g, n->preview, paths, count);
            continue;
        }
        if (n->kind != GK_NODE || !n->desc->export_text) continue;
        for (int k = 0; ok && k < n->desc->num_params; k++)
            if (n->desc->params[k].flags & NPRFX_PARAM_EXPORT)
                ok = push_output(g, n->params[k].s, paths, count);
    }
    if (ok) return NPRFX_OK;
    nprfx_graph_output_patterns_free(*paths, *count);
    *paths = NULL;
    *count = 0;
    return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY,
                       "out of memory listing the graph's outputs");
}

void nprfx_graph_output_patterns_free(char **paths, int count)
{
    for (int i = 0; i < count; i++)
        free(paths[i]);
    free(paths);
}
