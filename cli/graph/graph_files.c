/* The files a graph reads and the shot it declares: what nprfx farm checks before it submits a
 * shot in chunks (every chunk must find its plates and see the same shot). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal_graph.h"

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
