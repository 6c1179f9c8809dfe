/* nprfx graph engine — cycle detection at load: one depth-first search over the whole graph with an
 * explicit stack, O(nodes + references), so neither the graph's depth nor its number of paths
 * matters (a per-node walk of every path gave up on wide fan-outs and let cycles through). A
 * cycle is reported with the names of the nodes on it, in the direction the data flows. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/graph.h"
#include "graph_cycles.h"
#include "graph_model.h"

enum { WHITE = 0, GREY = 1 /* on the current path */, BLACK = 2 /* done, no cycle below */ };

typedef struct visit {
    int node, next_input;
} visit;

/* The message for the cycle made of path[from..top] closed by path[top] reading path[from]:
 * path[j] reads path[j + 1], so the data flows from the top of the path down to path[from]. */
static nprfx_result report_cycle(nprfx_graph *g, const visit *path, int from, int top)
{
    char list[640] = "";
    size_t len = 0;
    int shown = 0, total = top - from + 1;
    for (int j = from;; j = j == from ? top : j - 1) {
        const char *name = g->nodes[path[j].node].name;
        if (len + strlen(name) + 40 >= sizeof list) {
            snprintf(list + len, sizeof list - len, " -> ... (%d nodes in all)", total);
            break;
        }
        len += (size_t)snprintf(list + len, sizeof list - len, "%s%s", shown ? " -> " : "", name);
        if (shown++ == total) break; /* back at the first node */
    }
    return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "the graph has a cycle: %s", list);
}

nprfx_result internal_graph_check_cycles(nprfx_graph *g)
{
    unsigned char *color = calloc((size_t)(g->count ? g->count : 1), 1);
    visit *path = malloc((size_t)(g->count ? g->count : 1) * sizeof *path);
    if (!color || !path) {
        free(color);
        free(path);
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    nprfx_result r = NPRFX_OK;
    for (int root = 0; root < g->count && !r; root++) {
        if (color[root] != WHITE) continue;
        int top = 0; /* a node is on the path at most once, so count slots suffice */
        path[0] = (visit){root, 0};
        color[root] = GREY;
        while (top >= 0 && !r) {
            visit *v = &path[top];
            const gnode *n = &g->nodes[v->node];
            if (v->next_input == n->ninputs) {
                color[v->node] = BLACK;
                top--;
                continue;
            }
            int s = n->inputs[v->next_input++].src;
            if (s < 0 || color[s] == BLACK) continue;
            if (color[s] == WHITE) {
                color[s] = GREY;
                path[++top] = (visit){s, 0};
                continue;
            }
            int from = top; /* s is on the path: the cycle runs from it to the top */
            while (path[from].node != s)
                from--;
            r = report_cycle(g, path, from, top);
        }
    }
    free(color);
    free(path);
    return r;
}
